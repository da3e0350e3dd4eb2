// A mesh shared by many bodies is kept once (CullideBroadphase::getMemoryStats): N GImpact tori with one shape,
// moving over a BVH landscape (GImpact-mesh pairs through the culler: setGImpactMeshCulling), keep one local geometry
// for the tori and one for the landscape, and per moving body only a small record, no world-space copy. The CPU
// reference culler is used (no GL needed).
#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace cullide::test {
namespace {

struct Kept {
    CullideMemoryStats memory;
    std::size_t culledPairs = 0;
};

/// `bodies` tori sharing one shape, resting on and moving over the landscape for a few detections.
Kept runSharedTori(int bodies) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(btScalar(0.6), btScalar(0.2), 24, 12, btScalar(0.01));
    btCollisionShape* landscape = shapes.landscape(24, btScalar(1.0), btScalar(0.3));
    btDefaultCollisionConfiguration config;
    CullideBroadphase broadphase(Settings{}, nullptr, referenceFactory());
    broadphase.setGImpactMeshCulling(true);
    CullideCollisionDispatcher dispatcher(&config, &broadphase);
    btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher);
    btCollisionWorld world(&dispatcher, &broadphase, &config);
    std::vector<std::unique_ptr<btCollisionObject>> objects;
    auto add = [&](btCollisionShape* shape, const btTransform& t) {
        objects.push_back(std::make_unique<btCollisionObject>());
        objects.back()->setCollisionShape(shape);
        objects.back()->setWorldTransform(t);
        world.addCollisionObject(objects.back().get());
    };
    add(landscape, btTransform::getIdentity());  // centred: 24 x 24 around the origin
    Kept kept;
    for (int step = 0; step < 4; ++step) {
        for (int i = 0; i < bodies; ++i) {
            const btScalar x = btScalar(-10 + (i % 10) * 2.0 + 0.1 * step), z = btScalar(-10 + (i / 10) * 2.0);
            const btTransform t(btQuaternion(btVector3(1, 0, 0), btScalar(0.2 * i + 0.05 * step)), btVector3(x, btScalar(0.0), z));
            if (step == 0)
                add(torus, t);
            else
                objects[static_cast<std::size_t>(i) + 1]->setWorldTransform(t);
        }
        world.performDiscreteCollisionDetection();
        kept.culledPairs += broadphase.getLastFrameStats().culledPairs;
    }
    kept.memory = broadphase.getMemoryStats();
    for (auto& o : objects) world.removeCollisionObject(o.get());
    return kept;
}

TEST(SharedMesh, ManyBodiesWithOneShapeKeepItsGeometryOnce) {
    const Kept few = runSharedTori(10), many = runSharedTori(100);
    for (const Kept* k : {&few, &many}) {
        const CullideMemoryStats& m = k->memory;
        std::printf("[ measure  ] shared mesh: %zu objects kept, %zu shapes (%zu bytes shared), %zu bytes of "
                    "records and world copies (%zu copies): %.0f bytes per object\n",
                    m.objects, m.shapes, m.sharedGeometryBytes, m.objectBytes, m.worldCopies,
                    double(m.objectBytes) / double(m.objects));
        EXPECT_GT(k->culledPairs, 0u) << "the tori must go through the culler";
        EXPECT_EQ(m.shapes, 2u) << "one geometry for all tori, one for the landscape";
        EXPECT_LE(m.worldCopies, 1u) << "moving bodies keep no world-space copy (the static landscape may)";
    }
    EXPECT_GE(many.memory.objects, 90u);
    EXPECT_EQ(many.memory.sharedGeometryBytes, few.memory.sharedGeometryBytes) << "shared bytes grow with bodies";
    // A torus's own geometry is ~40 KB; what each body adds is its record only.
    const double perBody = double(many.memory.objectBytes - few.memory.objectBytes) /
                           double(many.memory.objects - few.memory.objects);
    EXPECT_LT(perBody, 1024.0);
}

}  // namespace
}  // namespace cullide::test
