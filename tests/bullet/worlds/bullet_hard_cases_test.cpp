// Numerical hard cases through Bullet (issue #6), in whichever precision Bullet was built with (the CI runs this
// file against Debian's float and float64 Bullet): coplanar resting faces of thin GImpact plates, and a GImpact
// scene far from the origin. CULLIDE against Bullet's default pipeline on identical states, every step.
#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

namespace cullide::test {
namespace {

/// A closed box as a GImpact triangle mesh (12 triangles), with its arrays.
struct GImpactBox {
    std::vector<btScalar> vertices;
    std::vector<int> indices;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btGImpactMeshShape> shape;

    GImpactBox(const btVector3& half, btScalar margin) {
        for (int i = 0; i < 8; ++i)
            vertices.insert(vertices.end(), {i & 1 ? half.x() : -half.x(), i & 2 ? half.y() : -half.y(),
                                             i & 4 ? half.z() : -half.z()});
        indices = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                   2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
        array = std::make_unique<btTriangleIndexVertexArray>(12, indices.data(), int(3 * sizeof(int)), 8,
                                                             vertices.data(), int(3 * sizeof(btScalar)));
        shape = std::make_unique<btGImpactMeshShape>(array.get());
        shape->setMargin(margin);
        shape->updateBound();
    }
};

MirrorOptions gimpactOptions(int steps) {
    MirrorOptions options;
    options.steps = steps;
    // As in the GImpact tori scene: the 4-point manifold keeps different points when triangle pairs come in a
    // different order; pairs with the plane (object 0) run Bullet's own algorithm on identical input.
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 ? 1e-6 : 2.0 * double(gContactBreakingThreshold);
    };
    return options;
}

TEST(BulletHardCases, ThinPlatesRestingFaceOnFace) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), 0);
    GImpactBox plate(btVector3(1, btScalar(0.02), btScalar(0.7)), btScalar(0.01));
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    for (TestWorld* w : {&reference, &cullide}) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w->dispatcher());
        w->addBody(plane, 0, btTransform::getIdentity());
        // A twisted stack, 0.5 mm apart: the plates settle face on face (coplanar, touching).
        for (int k = 0; k < 5; ++k)
            w->addBody(plate.shape.get(), 1,
                       btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.2) * btScalar(k)),
                                   btVector3(btScalar(0.05) * btScalar(k), btScalar(0.0205 + 0.0405 * k), 0)));
    }
    const MirrorRun run = runMirrored(reference, cullide, gimpactOptions(150));
    printMirrorRun("thin plates", run);
    expectAgreement(run, 300);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u);
}

/// Five 4 cm GImpact plates dropped 20 cm onto each other: on impact they interpenetrate by more than their
/// thickness, and GImpact's clip method then also makes penetration contacts from triangle pairs far apart.
MirrorRun dropThinPlates(bool deepPenetrationFallback) {
    ShapeStore shapes;
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), 0);
    GImpactBox plate(btVector3(1, btScalar(0.02), btScalar(0.7)), btScalar(0.01));
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    cullide.cullideBroadphase()->setDeepPenetrationFallback(deepPenetrationFallback);
    for (TestWorld* w : {&reference, &cullide}) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w->dispatcher());
        w->addBody(plane, 0, btTransform::getIdentity());
        for (int k = 0; k < 5; ++k)
            w->addBody(plate.shape.get(), 1,
                       btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.3) * btScalar(k)),
                                   btVector3(btScalar(0.05) * btScalar(k), btScalar(0.1 + 0.24 * k), 0)));
    }
    return runMirrored(reference, cullide, gimpactOptions(120));
}

TEST(BulletHardCases, ThinPlatesDroppedInterpenetrateLikeWithBullet) {
    CULLIDE_BULLET_REQUIRE_GL();
    const MirrorRun run = dropThinPlates(true);
    printMirrorRun("thin plates dropped, deep-penetration fallback on", run);
    expectAgreement(run, 300);
    EXPECT_GT(run.penetrationPairs, 0u) << "the plates never interpenetrated: the scene tests nothing";
    EXPECT_GT(run.cullidePairsFromTriangles, run.penetrationPairs);  // resting pairs still use the culled lists

    // Without the fallback the deviation the fallback removes is there (this scene can fail).
    const MirrorRun without = dropThinPlates(false);
    printMirrorRun("thin plates dropped, deep-penetration fallback off", without);
    EXPECT_EQ(without.agreement.missingPairs, 0u) << without.agreement.firstMissing;
    EXPECT_EQ(without.penetrationPairs, 0u);
    EXPECT_GT(without.agreement.depthMismatches + without.triangleContactsMissing, 0u);
}

TEST(BulletHardCases, GImpactSceneFarFromTheOrigin) {
    CULLIDE_BULLET_REQUIRE_GL();
    // float: 1e4 (a float ulp there is ~1e-3, a tenth of the margin); double: 1e6.
    const btScalar offset = sizeof(btScalar) == 8 ? btScalar(1e6) : btScalar(1e4);
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    GImpactBox floor(btVector3(6, btScalar(0.5), 6), btScalar(0.04));
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    const btVector3 origin(offset, btScalar(0.25) * offset, -offset);
    for (TestWorld* w : {&reference, &cullide}) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w->dispatcher());
        w->addBody(floor.shape.get(), 0, btTransform(btQuaternion::getIdentity(), origin - btVector3(0, btScalar(0.5), 0)));
        for (int k = 0; k < 5; ++k)
            w->addBody(torus, 1,
                       btTransform(btQuaternion(btVector3(1, 0, btScalar(0.3) * btScalar(k % 3)).normalized(),
                                                btScalar(0.5) + btScalar(0.7) * btScalar(k)),
                                   origin + btVector3(btScalar(0.3) * std::sin(btScalar(k)),
                                                      btScalar(1.5) + btScalar(1.7) * btScalar(k), 0)));
    }
    // The floor is object 0 here but a GImpact mesh, not a plane: its pairs use CULLIDE's triangle lists too.
    MirrorOptions options = gimpactOptions(200);
    options.tolerance = [](const std::pair<int, int>&) { return 2.0 * double(gContactBreakingThreshold); };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("far from the origin", run);
    expectAgreement(run, 200);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u);
}

}  // namespace
}  // namespace cullide::test
