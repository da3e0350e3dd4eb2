// Scene 2: GImpact tori falling on each other, on a static plane, on a BVH triangle-mesh landscape and on boxes
// with a kinematic torus; a deforming GImpact mesh. The application registers GImpact's algorithm on the dispatcher
// as it must with Bullet's own dispatcher; CULLIDE's surviving triangle pairs are what reaches
// collide_sat_triangles (GImpact-GImpact) and gimpact_vs_concave (GImpact-mesh).
#include "SceneSupport.h"
#include "TorusScene.h"
#include "narrowphase/ApartPairs.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btScaledBvhTriangleMeshShape.h>
#include <gtest/gtest.h>

#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

namespace cullide::test {
namespace {

TEST(BulletGImpact, ToriNoContactMissingAndContactsAgree) {
    CULLIDE_BULLET_REQUIRE_GL();
    TorusScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    scene.populate(reference);
    scene.populate(cullide);
    MirrorOptions options;
    options.steps = 200;
    // Torus-torus contacts come from CULLIDE's triangle pairs in sorted order, Bullet's from its box-tree order;
    // the manifold (rebuilt every frame by GImpact) keeps 4 points out of many and merges points closer than the
    // breaking threshold, so the retained deepest point may differ by up to that threshold. Torus-plane pairs run
    // Bullet's own algorithm on identical input: exact.
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 ? 1e-6 : 2.0 * double(gContactBreakingThreshold);
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("gimpact tori", run);
    expectCulledAgreement(run, 300);
}

/// GImpact tori falling on a static btBvhTriangleMeshShape landscape, with GImpact-mesh culling on: Bullet's
/// GImpact-vs-concave path (a BVH query of the torus and a convex-convex test per landscape triangle under it) runs on
/// CULLIDE's surviving landscape triangles only.
TEST(BulletGImpact, ToriOnATriangleMeshLandscape) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(24, btScalar(0.5), btScalar(0.5));
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 5; ++k)
            w.addBody(torus, 1,
                      btTransform(btQuaternion(btVector3(1, btScalar(0.2) * btScalar(k), 0).normalized(),
                                               btScalar(0.3) + btScalar(0.6) * btScalar(k)),
                                  btVector3(btScalar(2.2) * std::sin(btScalar(1.7) * btScalar(k)),
                                            btScalar(1.6) + btScalar(1.1) * btScalar(k),
                                            btScalar(2.2) * std::cos(btScalar(1.1) * btScalar(k)))));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    cullide.cullideBroadphase()->setGImpactMeshCulling(true);  // the culled GImpact-mesh path
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150;
    // Landscape triangles come in sorted order instead of the BVH's. GImpact's manifold (rebuilt every frame) merges
    // a new point into an existing one within the breaking threshold t and keeps 4 points, both in insertion order,
    // so the deepest retained point may differ by the depth change across a merge radius on a sloped landscape
    // (measured up to 0.044 = 2.2 t); every (pair, triangle) contact key is compared exactly.
    options.tolerance = [](const std::pair<int, int>&) { return 3.0 * double(gContactBreakingThreshold); };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("gimpact tori on a triangle-mesh landscape", run);
    expectCulledAgreement(run, 300);
}

/// The same with the landscape as a btScaledBvhTriangleMeshShape (non-uniform scale, as applications reuse one BVH
/// at several sizes): its triangles enter the culler scaled exactly as Bullet's scaled callback scales them, so the
/// GImpact-mesh pairs go through CULLIDE's triangle lists with every contact key of the default pipeline.
TEST(BulletGImpact, ToriOnAScaledTriangleMeshLandscape) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    auto* bvh = static_cast<btBvhTriangleMeshShape*>(shapes.landscape(24, btScalar(0.5), btScalar(0.5)));
    btScaledBvhTriangleMeshShape ground(bvh, btVector3(btScalar(1.3), btScalar(0.7), btScalar(0.9)));
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(&ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 5; ++k)
            w.addBody(torus, 1,
                      btTransform(btQuaternion(btVector3(1, btScalar(0.3) * btScalar(k), 0).normalized(),
                                               btScalar(0.2) + btScalar(0.7) * btScalar(k)),
                                  btVector3(btScalar(2.4) * std::sin(btScalar(1.3) * btScalar(k)),
                                            btScalar(1.2) + btScalar(1.0) * btScalar(k),
                                            btScalar(2.4) * std::cos(btScalar(0.9) * btScalar(k)))));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // every pair through the culler, as above
    cullide.cullideBroadphase()->setGImpactMeshCulling(true);
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150;
    options.tolerance = [](const std::pair<int, int>&) { return 3.0 * double(gContactBreakingThreshold); };  // as above
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("gimpact tori on a scaled triangle-mesh landscape", run);
    expectCulledAgreement(run, 300);
}

/// Convex hulls on the scaled landscape with convex-mesh culling on: the hull-mesh pairs read the culler's scaled
/// triangles (Bullet's btConvexConcaveCollisionAlgorithm on the surviving ones), every contact of the default pipeline
/// kept.
TEST(BulletGImpact, HullsOnAScaledTriangleMeshLandscape) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    auto* bvh = static_cast<btBvhTriangleMeshShape*>(shapes.landscape(24, btScalar(0.5), btScalar(0.5)));
    btScaledBvhTriangleMeshShape ground(bvh, btVector3(btScalar(0.8), btScalar(1.4), btScalar(1.1)));
    btCollisionShape* hull = shapes.hull(btVector3(btScalar(0.5), btScalar(0.35), btScalar(0.4)), 30, 7);
    auto populate = [&](TestWorld& w) {
        w.addBody(&ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 8; ++k)
            w.addBody(hull, 1,
                      btTransform(btQuaternion(btVector3(0, 1, btScalar(0.2) * btScalar(k)).normalized(),
                                               btScalar(0.5) * btScalar(k)),
                                  btVector3(btScalar(-3.5) + btScalar(k), btScalar(1.5) + btScalar(0.3) * btScalar(k),
                                            btScalar(1.2) * std::sin(btScalar(k)))));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the hull-mesh triangle path (off by default)
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 120;
    options.tolerance = [](const std::pair<int, int>&) { return double(gContactBreakingThreshold); };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("hulls on a scaled triangle-mesh landscape", run);
    expectAgreement(run, 300);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u) << "no hull-mesh pair read the culler's triangles";
}

/// GImpact tori falling on boxes (a static box floor and dynamic boxes), with a kinematic GImpact torus sweeping
/// through them: torus-box pairs run Bullet's GImpact-vs-convex path on CULLIDE's object pairs, torus-torus pairs
/// (the kinematic one included) CULLIDE's triangle lists.
TEST(BulletGImpact, ToriOnBoxesWithAKinematicTorus) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* floor = shapes.box(btVector3(8, btScalar(0.5), 8));
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.6), btScalar(0.3), btScalar(0.5)));
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    constexpr int kKinematic = 10;  // object index of the kinematic torus
    auto kinematicPose = [](int step) {
        return btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.02) * btScalar(step)),
                           btVector3(btScalar(-5.0 + 0.07 * step), btScalar(0.75), btScalar(0.3)));
    };
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(floor, 0, btTransform(btQuaternion::getIdentity(), btVector3(0, btScalar(-0.5), 0)));
        for (int k = 0; k < 4; ++k)  // objects 1-4
            w.addBody(box, 2,
                      btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.4) * btScalar(k)),
                                  btVector3(btScalar(1.7) * btScalar(k) - btScalar(2.5), btScalar(0.3),
                                            btScalar(0.8) * btScalar(k % 2))));
        for (int k = 0; k < 5; ++k)  // objects 5-9
            w.addBody(torus, 1,
                      btTransform(btQuaternion(btVector3(1, 0, btScalar(0.3) * btScalar(k)).normalized(),
                                               btScalar(0.4) + btScalar(0.8) * btScalar(k)),
                                  btVector3(btScalar(1.6) * btScalar(k) - btScalar(3.2),
                                            btScalar(2.0) + btScalar(0.6) * btScalar(k), btScalar(0.4) * btScalar(k % 3))));
        btRigidBody* kinematic = w.addBody(torus, 0, kinematicPose(0));  // object 10
        kinematic->setCollisionFlags(kinematic->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
        kinematic->setActivationState(DISABLE_DEACTIVATION);
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150;
    // Torus-torus pairs: CULLIDE's sorted triangle order (GImpact's 4-point manifold keeps other points, as in the
    // other torus scenes); torus-box pairs run Bullet's own algorithm on identical input.
    options.tolerance = [&](const std::pair<int, int>& pair) {
        return pair.first >= 5 ? 2.0 * double(gContactBreakingThreshold) : 1e-6;
    };
    options.before = [&](int step, TestWorld& ref, TestWorld&) {
        ref.objectByIndex(kKinematic)->setWorldTransform(kinematicPose(step));  // mirrored to CULLIDE's world
    };
    std::size_t kinematicPairSteps = 0;  // pair-steps with contacts between the kinematic torus and the others
    options.each = [&](int, TestWorld& ref, TestWorld&) {
        for (const auto& entry : contactsOf(ref.world()))
            if (entry.first.second == kKinematic) ++kinematicPairSteps;
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("gimpact tori on boxes, kinematic torus", run);
    std::printf("  the kinematic torus had contacts in %zu pair-steps\n", kinematicPairSteps);
    expectCulledAgreement(run, 300);
    EXPECT_GT(kinematicPairSteps, 20u) << "the kinematic torus never swept into the pile: the scene tests nothing";
}

/// The dispatcher's GImpact per-triangle loop (GImpact-convex and GImpact-concave pairs), summed over a mirrored run.
struct LoopCounts {
    std::size_t convexPairs = 0, concavePairs = 0, candidates = 0, tested = 0, unchecked = 0;
    std::function<void(int, TestWorld&, TestWorld&)> collector() {
        return [this](int, TestWorld&, TestWorld& c) {
            const CullideDispatchStats& d = c.cullideDispatcher()->getLastStepStats();
            convexPairs += d.convexPairs;
            concavePairs += d.concavePairs;
            candidates += d.convexCandidates;
            tested += d.convexTriangles;
            unchecked += d.convexUnchecked;
        };
    }
};

/// GImpact tori on a large tilted ground box, with hulls and spheres among them. Bullet's query box for a torus is
/// the ground's AABB in the torus's frame, which holds nearly all of the torus: CULLIDE's dispatcher runs Bullet's
/// per-triangle loop on the triangles within reach of the convex shape only. Every contact point (position,
/// normal, distance, triangle) must be Bullet's; with GImpact-convex culling on as off (the default). At `scale` 1
/// most candidate triangles must have been skipped. The scene shrunk by `scale` (sizes, margins, positions and
/// gravity alike) keeps Bullet's absolute breaking threshold (0.02), whose reach then covers whole tori: there the
/// dispatcher must leave out its per-triangle test, which would keep every candidate.
void expectConvexContactsFromTrianglesWithinReach(bool convexCulling, btScalar scale = 1) {
    ShapeStore shapes;
    const btScalar margin = btScalar(0.04) * scale;  // Bullet's default, scaled
    btCollisionShape* ground = shapes.box(btVector3(12, btScalar(0.5), 12) * scale);
    btCollisionShape* torus = shapes.gimpactTorus(scale, btScalar(0.3) * scale, 24, 12, margin);
    btCollisionShape* hull = shapes.hull(btVector3(btScalar(0.5), btScalar(0.35), btScalar(0.4)) * scale, 30, 7);
    btCollisionShape* ball = shapes.sphere(btScalar(0.35) * scale);
    ground->setMargin(margin);
    hull->setMargin(margin);
    const btQuaternion tilt(btVector3(1, 0, 1).normalized(), btScalar(0.12));
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.world().setGravity(btVector3(0, -10, 0) * scale);
        w.addBody(ground, 0, btTransform(tilt, btVector3(0, -1, 0) * scale));
        for (int k = 0; k < 6; ++k) {
            const btVector3 at(btScalar(1.9) * std::sin(btScalar(1.3) * btScalar(k)), btScalar(1.0) + btScalar(0.9) * btScalar(k),
                               btScalar(1.9) * std::cos(btScalar(0.9) * btScalar(k)));
            const btQuaternion turn(btVector3(1, 0, btScalar(0.4)).normalized(), btScalar(0.3) * btScalar(k));
            w.addBody(torus, 1, btTransform(turn, at * scale));
            w.addBody(k % 2 ? hull : ball, 1,
                      btTransform(btQuaternion::getIdentity(), (at + btVector3(0, btScalar(0.6), 0)) * scale));
        }
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    cullide.cullideBroadphase()->setGImpactConvexCulling(convexCulling);
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150;
    // Torus-torus pairs come from CULLIDE's sorted triangle pairs (see ToriNoContactMissingAndContactsAgree); every
    // pair with a convex shape runs Bullet's own per-triangle loop: exact, point by point.
    auto isTorus = [](int object) { return object >= 1 && object % 2 == 1; };
    options.tolerance = [&](const std::pair<int, int>& pair) {
        return isTorus(pair.first) && isTorus(pair.second) ? 2.0 * double(gContactBreakingThreshold) : 1e-6 * scale;
    };
    LoopCounts counts;
    options.each = counts.collector();
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("gimpact tori, hulls and spheres on a tilted ground box", run);
    std::printf("  GImpact-convex: %zu pair-steps, %zu of %zu candidate triangles within reach, %zu unchecked\n",
                counts.convexPairs, counts.tested, counts.candidates, counts.unchecked);
    const std::size_t convexPairs = counts.convexPairs, tested = counts.tested, candidates = counts.candidates;
    expectAgreement(run, 600);
    EXPECT_GT(convexPairs, 300u) << "no GImpact-convex pair ran: the scene tests nothing";
    EXPECT_GT(tested, 0u);
    if (scale == 1) {
        EXPECT_LT(tested * 4, candidates) << "the reach filter kept most of Bullet's candidates";
        EXPECT_EQ(counts.unchecked, 0u) << "no torus lies wholly within reach of a convex shape at this scale";
    } else {
        EXPECT_EQ(counts.unchecked, candidates) << "the reach covers every torus: the per-triangle test is waste";
    }
}

TEST(BulletGImpact, ConvexShapesGetBulletsContactsFromTrianglesWithinReach) {
    CULLIDE_BULLET_REQUIRE_GL();
    expectConvexContactsFromTrianglesWithinReach(false);
}

TEST(BulletGImpact, ConvexShapesCulledGetBulletsContactsFromTrianglesWithinReach) {
    CULLIDE_BULLET_REQUIRE_GL();
    expectConvexContactsFromTrianglesWithinReach(true);
}

TEST(BulletGImpact, ConvexShapesInASmallUnitWorldGetBulletsContactsWithoutThePerTriangleTest) {
    CULLIDE_BULLET_REQUIRE_GL();
    expectConvexContactsFromTrianglesWithinReach(false, btScalar(1e-3));
}

/// GImpact tori dropped on a static concave ground (turned, off the origin), added before the tori (the ground is
/// body 0 of its pairs) or after them. By default (no GImpact-mesh culling) the dispatcher runs Bullet's gimpact_vs_concave itself, with the
/// torus triangles out of reach of each ground triangle skipped: every contact point (position, normal, distance,
/// triangle of both sides) must be Bullet's, and candidates must have been skipped.
void expectConcaveContactsAsBullets(btCollisionShape* ground, bool groundFirst, const char* what) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    // Turned and moved off the origin: the GImpact part's box must be mapped into the ground's frame.
    const btTransform pose(btQuaternion(btVector3(0, 1, 0), btScalar(0.3)),
                           btVector3(btScalar(0.4), btScalar(-0.2), btScalar(-0.3)));
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        if (groundFirst) w.addBody(ground, 0, pose);
        for (int k = 0; k < 5; ++k)
            w.addBody(torus, 1,
                      btTransform(btQuaternion(btVector3(1, btScalar(0.25) * btScalar(k), 0).normalized(),
                                               btScalar(0.4) + btScalar(0.5) * btScalar(k)),
                                  btVector3(btScalar(2.3) * std::sin(btScalar(1.5) * btScalar(k)),
                                            btScalar(1.5) + btScalar(1.0) * btScalar(k),
                                            btScalar(2.3) * std::cos(btScalar(1.2) * btScalar(k)))));
        if (!groundFirst) w.addBody(ground, 0, pose);
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150;  // exact tolerance: point by point
    LoopCounts counts;
    options.each = counts.collector();
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun(what, run);
    std::printf("  GImpact-concave: %zu pair-steps, %zu of %zu candidate triangles within reach\n",
                counts.concavePairs, counts.tested, counts.candidates);
    const std::size_t concavePairs = counts.concavePairs, tested = counts.tested, candidates = counts.candidates;
    expectAgreement(run, 200);
    EXPECT_GT(run.agreement.pointComparedPairs, 200u) << "contacts must be compared point by point";
    EXPECT_GT(concavePairs, 200u) << "no GImpact-concave pair ran the reproduction";
    EXPECT_EQ(run.cullidePairsFromTriangles, 0u) << "GImpact-mesh pairs are not culled by default";
    EXPECT_GT(tested, 0u);
    EXPECT_LT(tested, candidates) << "no candidate out of reach was skipped";
}

TEST(BulletGImpact, TriangleMeshGroundGetsBulletsContactsPointForPoint) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(24, btScalar(0.5), btScalar(0.5));
    expectConcaveContactsAsBullets(ground, true, "gimpact tori on a BVH mesh (ground body 0), default");
    expectConcaveContactsAsBullets(ground, false, "gimpact tori on a BVH mesh (ground body 1), default");
}

TEST(BulletGImpact, ScaledMeshAndHeightfieldGroundsGetBulletsContactsPointForPoint) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    auto* bvh = static_cast<btBvhTriangleMeshShape*>(shapes.landscape(24, btScalar(0.5), btScalar(0.5)));
    btScaledBvhTriangleMeshShape scaled(bvh, btVector3(btScalar(1.3), btScalar(0.7), btScalar(0.9)));
    expectConcaveContactsAsBullets(&scaled, true, "gimpact tori on a scaled BVH mesh, default");
    const int side = 33;
    std::vector<float> heights(static_cast<std::size_t>(side * side));
    for (int z = 0; z < side; ++z)
        for (int x = 0; x < side; ++x)
            heights[static_cast<std::size_t>(z * side + x)] =
                0.4f * std::sin(0.5f * float(x)) * std::cos(0.4f * float(z));
    // The float constructor (the legacy one reads PHY_FLOAT data as doubles in a double-precision Bullet).
    btHeightfieldTerrainShape field(side, side, heights.data(), btScalar(-0.4), btScalar(0.4), 1, false);
    field.setLocalScaling(btVector3(btScalar(0.4), 1, btScalar(0.4)));
    expectConcaveContactsAsBullets(&field, false, "gimpact tori on a heightfield, default");
}

TEST(BulletGImpact, WithoutRegisterAlgorithmMeshPairsStayEmptyLikeBullet) {
    CULLIDE_BULLET_REQUIRE_GL();
    // Bullet's default matrix has no GImpact-GImpact algorithm until registerAlgorithm is called: CULLIDE's
    // dispatcher keeps that meaning (no contacts), it does not silently switch GImpact on.
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 16, 8, btScalar(0.04));
    TestWorld w(PipelineKind::Cullide);
    w.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    w.world().setGravity(btVector3(0, 0, 0));
    w.addBody(torus, 1, btTransform::getIdentity());
    w.addBody(torus, 1, btTransform(btQuaternion(btVector3(1, 0, 0), SIMD_HALF_PI), btVector3(btScalar(1.6), 0, 0)));
    w.detectCollisions();
    EXPECT_EQ(w.world().getBroadphase()->getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    EXPECT_TRUE(contactsOf(w.world()).empty());
    btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
    // Algorithms are created once per pair: a fresh pair (remove + re-add) picks up the registration.
    btCollisionObject* second = w.objectByIndex(1);
    w.world().removeCollisionObject(second);
    w.world().addCollisionObject(second);
    w.detectCollisions();
    const ContactMap contacts = contactsOf(w.world());
    ASSERT_EQ(contacts.size(), 1u);
    EXPECT_LT(contacts.begin()->second.minDistance, 0.0);  // interlocked tori penetrate
    EXPECT_GT(w.cullideDispatcher()->getLastStepStats().cullidePairs, 0u);
}

}  // namespace
}  // namespace cullide::test

namespace cullide::test {
namespace {

/// Scales every vertex of a GImpact mesh in place, the way an application deforms one: write the vertex buffer,
/// then postUpdate() + updateBound() as Bullet requires. No CULLIDE call.
void scaleInPlace(btCollisionShape* shape, const std::vector<btScalar>& original, btScalar factor) {
    auto* mesh = static_cast<btGImpactMeshShape*>(shape);
    btStridingMeshInterface* interface = mesh->getMeshPart(0)->getTrimeshPrimitiveManager()->m_meshInterface;
    unsigned char* vertexBase = nullptr;
    unsigned char* indexBase = nullptr;
    int numVerts = 0, stride = 0, indexStride = 0, numFaces = 0;
    PHY_ScalarType type = PHY_FLOAT, indexType = PHY_INTEGER;
    interface->getLockedVertexIndexBase(&vertexBase, numVerts, type, stride, &indexBase, indexStride, numFaces,
                                        indexType, 0);
    for (int v = 0; v < numVerts; ++v) {
        auto* p = reinterpret_cast<btScalar*>(vertexBase + static_cast<std::ptrdiff_t>(v) * stride);
        for (int k = 0; k < 3; ++k) p[k] = original[static_cast<std::size_t>(3 * v + k)] * factor;
    }
    interface->unLockVertexBase(0);
    mesh->postUpdate();
    mesh->updateBound();
}

TEST(BulletGImpact, DeformingMeshNeedsNoExtraCall) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* breathing = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    btCollisionShape* still = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    std::vector<btScalar> original;
    {
        auto* mesh = static_cast<btGImpactMeshShape*>(breathing);
        btGImpactMeshShapePart* part = mesh->getMeshPart(0);
        part->lockChildShapes();
        for (int v = 0; v < part->getVertexCount(); ++v) {
            btVector3 p;
            part->getVertex(v, p);
            original.insert(original.end(), {p.x(), p.y(), p.z()});
        }
        part->unlockChildShapes();
    }
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.world().setGravity(btVector3(0, 0, 0));
        w.addBody(still, 0, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(2.7), 0, 0)));
        w.addBody(breathing, 1, btTransform::getIdentity());
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 120;
    options.tolerance = [](const std::pair<int, int>&) { return 2.0 * double(gContactBreakingThreshold); };
    // Outer radius 1.3 * factor against a neighbour 2.7 away: out of contact, touching, overlapping, and back.
    options.before = [&](int step, TestWorld& ref, TestWorld&) {
        scaleInPlace(breathing, original, btScalar(1.0 + 0.12 * std::sin(0.1 * step)));
        // Keep the breathing torus in place (contacts push it away); the mirror copies this state to CULLIDE's world.
        if (btRigidBody* body = btRigidBody::upcast(ref.world().getCollisionObjectArray()[1])) {
            body->setWorldTransform(btTransform::getIdentity());
            body->setLinearVelocity(btVector3(0, 0, 0));
            body->setAngularVelocity(btVector3(0, 0, 0));
        }
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("deforming gimpact torus", run);
    expectAgreement(run, 20);
}

}  // namespace
}  // namespace cullide::test

namespace cullide::test {
namespace {

/// Random poses around a torus of major radius 0.8 lying in the xz plane (xorshift, seeded: the same in every run).
class Poses {
public:
    explicit Poses(std::uint64_t seed) : m_state(seed) {}
    btTransform next() {
        const btVector3 axis(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
        const btQuaternion turn(axis.normalized(), uniform(0, 6.28));
        const btScalar x = uniform(-1.3, 1.3), y = uniform(-0.6, 0.6), z = uniform(-1.3, 1.3);
        return btTransform(turn, btVector3(x, y, z));
    }

private:
    btScalar uniform(double lo, double hi) {
        m_state ^= m_state << 13;
        m_state ^= m_state >> 7;
        m_state ^= m_state << 17;
        return btScalar(lo + (hi - lo) * double(m_state >> 11) * (1.0 / 9007199254740992.0));
    }
    std::uint64_t m_state;
};

/// Every point a contact query reports: distance, positions and the shape identifiers, in order.
struct QueryPoints final : btCollisionWorld::ContactResultCallback {
    std::vector<btScalar> values;
    int beyondThreshold = 0;  ///< points farther than their pair's manifold breaking threshold (a world drops them)
    btScalar threshold = 0;
    btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper*, int part0, int index0,
                             const btCollisionObjectWrapper*, int part1, int index1) override {
        values.insert(values.end(), {cp.getDistance(), cp.m_positionWorldOnA.x(), cp.m_positionWorldOnA.y(),
                                     cp.m_positionWorldOnA.z(), cp.m_normalWorldOnB.x(), cp.m_normalWorldOnB.y(),
                                     cp.m_normalWorldOnB.z(), btScalar(part0), btScalar(index0), btScalar(part1),
                                     btScalar(index1)});
        beyondThreshold += cp.getDistance() > threshold ? 1 : 0;
        return 0;
    }
};

// contactTest and contactPairTest hand the algorithm Bullet's btBridgedManifoldResult, which checks no breaking
// threshold: a triangle the swap's GImpact paths skip as out of the manifold's reach still makes a point there (an
// outside probe found a compound's box child missing points). Their results must be Bullet's, point for point.
TEST(BulletGImpact, ContactQueriesGetBulletsPoints) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(btScalar(0.8), btScalar(0.25), 24, 12, btScalar(0.04));
    btCompoundShape compound;
    compound.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.3), 0, 0)),
                           shapes.box(btVector3(btScalar(0.3), btScalar(0.2), btScalar(0.2))));
    btCollisionShape* others[] = {&compound, shapes.box(btVector3(btScalar(0.1), btScalar(0.1), btScalar(0.1))),
                                  shapes.sphere(btScalar(0.1)),
                                  shapes.hull(btVector3(btScalar(0.3), btScalar(0.2), btScalar(0.25)), 20, 5)};
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->add(torus, btTransform::getIdentity());
        for (btCollisionShape* s : others) w->add(s, btTransform(btQuaternion::getIdentity(), btVector3(9, 9, 9)));
    }
    Poses poses(12345);
    int differing = 0, withPoints = 0, beyond = 0;
    for (int pose = 0; pose < 400; ++pose) {
        const std::size_t k = 1 + std::size_t(pose) % 4;
        const btTransform t = poses.next();
        QueryPoints got[2][2];
        CollisionOnlyWorld* worlds[2] = {&reference, &cullide};
        for (int w = 0; w < 2; ++w) {
            worlds[w]->object(k).setWorldTransform(t);
            worlds[w]->world().updateAabbs();
            for (QueryPoints& q : got[w])
                q.threshold = bullet::manifoldBreakingThreshold(worlds[w]->dispatcher(), worlds[w]->object(0),
                                                                worlds[w]->object(k));
            worlds[w]->world().contactTest(&worlds[w]->object(k), got[w][0]);
            worlds[w]->world().contactPairTest(&worlds[w]->object(0), &worlds[w]->object(k), got[w][1]);
            worlds[w]->object(k).setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(9, 9, 9)));
        }
        for (int q = 0; q < 2; ++q) {
            const std::vector<btScalar>& a = got[0][q].values;
            const std::vector<btScalar>& b = got[1][q].values;
            const bool same = a.size() == b.size() &&
                              (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(btScalar)) == 0);
            differing += same ? 0 : 1;
        }
        if (k == 1) {  // the compound: the one whose child reaches the adapter's GImpact algorithm in a query
            withPoints += got[0][1].values.empty() ? 0 : 1;
            beyond += got[0][1].beyondThreshold;
        }
    }
    std::printf("[ measure  ] contact queries: %d of 100 compound poses with points, %d points beyond the breaking "
                "threshold; %d of 800 query results differ\n",
                withPoints, beyond, differing);
    EXPECT_GT(withPoints, 25);
    EXPECT_GT(beyond, 10) << "the queries must report points a world's manifold would drop";
    EXPECT_EQ(differing, 0);
}

// With convex-mesh culling on, a compound's hull child against a BVH mesh reads the culler's surviving triangles while
// the pair's record holds (same transforms as the step). A contact query right after the step asks the same
// algorithm with btBridgedManifoldResult, which accepts points beyond the breaking threshold, so beyond what the
// culler's margin covers when the mesh has a margin of its own: the query gets Bullet's algorithm on every triangle.
TEST(BulletGImpact, ContactQueriesOnCulledConvexMeshPairsGetBulletsPoints) {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(8, btScalar(1), btScalar(0.4));
    ground->setMargin(btScalar(0.06));
    btCompoundShape compound;
    compound.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.2), 0, 0)),
                           shapes.hull(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35)), 20, 5));
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    static_cast<CullideBroadphase*>(cullide.world().getBroadphase())->setConvexMeshCulling(true);
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->add(ground, btTransform(btQuaternion::getIdentity(), btVector3(-4, 0, -4)));
        w->add(&compound, btTransform::getIdentity())->setCollisionFlags(0);
    }
    Poses poses(4242);
    int differing = 0, withPoints = 0, beyond = 0;
    for (int pose = 0; pose < 200; ++pose) {
        btTransform t = poses.next();
        t.getOrigin().setY(t.getOrigin().y() * btScalar(0.5) + btScalar(0.1));  // near the ground's surface
        QueryPoints got[2];
        CollisionOnlyWorld* worlds[2] = {&reference, &cullide};
        for (int w = 0; w < 2; ++w) {
            worlds[w]->object(1).setWorldTransform(t);
            worlds[w]->world().performDiscreteCollisionDetection();  // the step: the culled pair's record
            got[w].threshold = bullet::manifoldBreakingThreshold(worlds[w]->dispatcher(), worlds[w]->object(0),
                                                                 worlds[w]->object(1));
            worlds[w]->world().contactPairTest(&worlds[w]->object(0), &worlds[w]->object(1), got[w]);
        }
        const std::vector<btScalar>& a = got[0].values;
        const std::vector<btScalar>& b = got[1].values;
        const bool same = a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(btScalar)) == 0);
        differing += same ? 0 : 1;
        withPoints += a.empty() ? 0 : 1;
        beyond += got[0].beyondThreshold;
    }
    const CullideFrameStats& frame = static_cast<CullideBroadphase*>(cullide.world().getBroadphase())->getLastFrameStats();
    std::printf("[ measure  ] culled convex-mesh queries: %d of 200 poses with points, %d points beyond the threshold, "
                "%d differ (last frame: %zu culled pairs)\n",
                withPoints, beyond, differing, frame.culledPairs);
    EXPECT_GT(withPoints, 50);
    EXPECT_GT(beyond, 10);
    EXPECT_EQ(differing, 0);
}

/// Every manifold's points (count, distance, positions, normal, shape identifiers), in the dispatcher's order.
std::vector<btScalar> manifoldValues(btCollisionDispatcher& d) {
    std::vector<btScalar> v;
    for (int i = 0; i < d.getNumManifolds(); ++i) {
        const btPersistentManifold& m = *d.getManifoldByIndexInternal(i);
        v.push_back(btScalar(m.getNumContacts()));
        for (int k = 0; k < m.getNumContacts(); ++k) {
            const btManifoldPoint& p = m.getContactPoint(k);
            v.insert(v.end(), {p.getDistance(), p.m_positionWorldOnA.x(), p.m_positionWorldOnA.y(),
                               p.m_positionWorldOnA.z(), p.m_positionWorldOnB.x(), p.m_positionWorldOnB.y(),
                               p.m_positionWorldOnB.z(), p.m_normalWorldOnB.x(), p.m_normalWorldOnB.y(),
                               p.m_normalWorldOnB.z(), btScalar(p.m_partId0), btScalar(p.m_index0),
                               btScalar(p.m_partId1), btScalar(p.m_index1)});
        }
    }
    return v;
}

// With SAT convex collision (btDispatcherInfo::m_enableSatConvex) and a polyhedral box (initializePolyhedralFeatures),
// Bullet's convex-triangle algorithm clips faces: GImpact against convex shapes then runs Bullet's algorithm as it is
// (an outside probe found other points, and other ones per thread count). Random poses of the box against a torus in
// a collision world: every manifold point Bullet's, at 1 and 2 threads.
TEST(BulletGImpact, SatConvexAgainstGImpactKeepsBulletsManifolds) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(btScalar(0.8), btScalar(0.25), 24, 12, btScalar(0.04));
    btBoxShape box(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35)));
    box.initializePolyhedralFeatures();
    for (const unsigned threads : {1u, 2u}) {
        CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
        static_cast<CullideCollisionDispatcher&>(cullide.dispatcher()).setNarrowPhaseThreads(threads);
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            w->world().getDispatchInfo().m_enableSatConvex = true;
            w->add(&box, btTransform::getIdentity());
            w->add(torus, btTransform::getIdentity());
        }
        Poses poses(777);
        int differing = 0, withPoints = 0;
        for (int pose = 0; pose < 300; ++pose) {
            const btTransform t = poses.next();
            for (CollisionOnlyWorld* w : {&reference, &cullide}) {
                w->object(0).setWorldTransform(t);
                w->world().performDiscreteCollisionDetection();
            }
            const std::vector<btScalar> a = manifoldValues(reference.dispatcher());
            const std::vector<btScalar> b = manifoldValues(cullide.dispatcher());
            const bool same =
                a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(btScalar)) == 0);
            differing += same ? 0 : 1;
            withPoints += a.size() > 1 ? 1 : 0;
        }
        std::printf("[ measure  ] SAT box against a GImpact torus, %u threads: %d of 300 poses with points, %d differ\n",
                    threads, withPoints, differing);
        EXPECT_GT(withPoints, 20);
        EXPECT_EQ(differing, 0) << threads << " threads";
    }
}

}  // namespace
}  // namespace cullide::test
