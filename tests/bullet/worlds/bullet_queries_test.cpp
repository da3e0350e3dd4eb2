// Scene 4: ray tests, convex sweeps and contact tests answered from CullideBroadphase's internal btDbvt, compared
// with btDbvtBroadphase on identical states.
#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

namespace cullide::test {
namespace {

struct QueryScene {
    ShapeStore shapes;
    void populate(TestWorld& w) {
        if (ground == nullptr) {
            ground = shapes.landscape(32, 1, btScalar(1.2));
            plane = shapes.plane(btVector3(0, 1, 0), -4);
            box = shapes.box(btVector3(btScalar(0.5), btScalar(0.3), btScalar(0.4)));
            sphere = shapes.sphere(btScalar(0.45));
            hull = shapes.hull(btVector3(btScalar(0.6), btScalar(0.5), btScalar(0.5)), 20, 3);
            torus = shapes.gimpactTorus(btScalar(0.8), btScalar(0.25), 16, 8, btScalar(0.04));
        }
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(ground, 0, btTransform::getIdentity());
        w.addBody(plane, 0, btTransform::getIdentity());
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> u(-12.0, 12.0);
        btCollisionShape* kinds[] = {box, sphere, hull, torus};
        for (int k = 0; k < 32; ++k) {
            const btVector3 p(btScalar(u(rng)), btScalar(3 + k % 4), btScalar(u(rng)));
            w.addBody(kinds[k % 4], 1, btTransform(btQuaternion(btScalar(k), btScalar(0.5 * k), 0), p));
        }
    }
    btCollisionShape* ground = nullptr;
    btCollisionShape* plane = nullptr;
    btCollisionShape* box = nullptr;
    btCollisionShape* sphere = nullptr;
    btCollisionShape* hull = nullptr;
    btCollisionShape* torus = nullptr;
};

struct Hit {
    int object;
    float fraction;
    friend bool operator<(const Hit& a, const Hit& b) {
        return a.object != b.object ? a.object < b.object : a.fraction < b.fraction;
    }
    friend bool operator==(const Hit& a, const Hit& b) { return a.object == b.object && a.fraction == b.fraction; }
};

std::vector<Hit> allHits(btCollisionWorld& w, const btVector3& from, const btVector3& to) {
    btCollisionWorld::AllHitsRayResultCallback cb(from, to);
    w.rayTest(from, to, cb);
    std::vector<Hit> hits;
    for (int i = 0; i < cb.m_collisionObjects.size(); ++i)
        hits.push_back({cb.m_collisionObjects[i]->getUserIndex(), float(cb.m_hitFractions[i])});
    std::sort(hits.begin(), hits.end());
    return hits;
}

Hit closestSweep(btCollisionWorld& w, const btConvexShape* shape, const btTransform& from, const btTransform& to) {
    btCollisionWorld::ClosestConvexResultCallback cb(from.getOrigin(), to.getOrigin());
    w.convexSweepTest(shape, from, to, cb);
    return {cb.hasHit() ? cb.m_hitCollisionObject->getUserIndex() : -1, float(cb.m_closestHitFraction)};
}

struct ContactSet : btCollisionWorld::ContactResultCallback {
    std::set<int> objects;
    btScalar addSingleResult(btManifoldPoint&, const btCollisionObjectWrapper* a, int, int,
                             const btCollisionObjectWrapper* b, int, int) override {
        objects.insert(a->getCollisionObject()->getUserIndex());
        objects.insert(b->getCollisionObject()->getUserIndex());
        return 0;
    }
};

TEST(BulletQueries, RayTestsSweepsAndContactTestsMatchDbvt) {
    CULLIDE_BULLET_REQUIRE_GL();
    QueryScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(cullide);
    btSphereShape probeSphere(btScalar(0.3));
    btBoxShape probeBox(btVector3(btScalar(0.4), btScalar(0.2), btScalar(0.3)));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-14.0, 14.0);
    std::size_t rays = 0, rayHits = 0, sweeps = 0, sweepHits = 0, contactTests = 0, contactHits = 0;
    MirrorOptions options;
    options.steps = 90;
    options.each = [&](int step, TestWorld& a, TestWorld& b) {
        if (step % 15 != 14) return;
        mirrorState(a, b);
        a.world().updateAabbs();
        b.world().updateAabbs();
        for (int r = 0; r < 150; ++r) {
            const btVector3 from(btScalar(u(rng)), btScalar(8), btScalar(u(rng)));
            const btVector3 to(btScalar(u(rng)), btScalar(-6), btScalar(u(rng)));
            const auto ha = allHits(a.world(), from, to);
            ASSERT_EQ(ha, allHits(b.world(), from, to)) << "ray " << r << " at step " << step;
            ++rays;
            rayHits += ha.size();
            // Horizontal rays through the objects' layer too.
            const btVector3 side0(btScalar(-15), btScalar(1 + r % 4), btScalar(u(rng)));
            const btVector3 side1(btScalar(15), btScalar(1 + (r + 1) % 4), btScalar(u(rng)));
            ASSERT_EQ(allHits(a.world(), side0, side1), allHits(b.world(), side0, side1));
        }
        for (int k = 0; k < 40; ++k) {
            const btTransform from(btQuaternion(btScalar(k), 0, 0), btVector3(btScalar(u(rng)), 7, btScalar(u(rng))));
            const btTransform to(btQuaternion(btScalar(k), 1, 0), btVector3(btScalar(u(rng)), -5, btScalar(u(rng))));
            const btConvexShape* shape = k % 2 == 0 ? static_cast<btConvexShape*>(&probeSphere) : &probeBox;
            const Hit ha = closestSweep(a.world(), shape, from, to);
            const Hit hb = closestSweep(b.world(), shape, from, to);
            ASSERT_EQ(ha.object, hb.object) << "sweep " << k << " at step " << step;
            ASSERT_EQ(ha.fraction, hb.fraction);
            ++sweeps;
            sweepHits += ha.object >= 0 ? 1 : 0;
        }
        for (int i = 2; i < a.nextIndex(); ++i) {
            ContactSet ca, cb;
            a.world().contactTest(a.objectByIndex(i), ca);
            b.world().contactTest(b.objectByIndex(i), cb);
            ASSERT_EQ(ca.objects, cb.objects) << "contactTest of object " << i << " at step " << step;
            ++contactTests;
            contactHits += ca.objects.empty() ? 0 : 1;
        }
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    std::printf("[queries] %zu ray tests (%zu hits), %zu convex sweeps (%zu hits), %zu contact tests (%zu touching): "
                "identical results\n",
                rays, rayHits, sweeps, sweepHits, contactTests, contactHits);
    EXPECT_GT(rayHits, rays / 2);
    EXPECT_GT(sweepHits, sweeps / 2);
    EXPECT_GT(contactHits, 0u);
    EXPECT_EQ(run.agreement.missingPairs, 0u) << run.agreement.firstMissing;
}

}  // namespace
}  // namespace cullide::test
