// Larger scenes for the measurements (ms per step of both pipelines), still checked like the small ones:
// many primitives and hulls on a bigger landscape, and a pile of GImpact tori.
#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace cullide::test {
namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr int kStepScale = 2;  // sanitizer builds: fewer steps, same checks
#else
constexpr int kStepScale = 1;
#endif

void printRenderer(TestWorld& w) {
    if (const CullideBroadphase* bp = w.cullideBroadphase())
        std::printf("  culler renderer: %s (%s), margin d = %.4f\n", bp->getLastFrameStats().culler.renderer.c_str(),
                    bp->getLastFrameStats().culler.device.c_str(), bp->getCullingMargin());
}

TEST(BulletScale, ManyObjectsOnLandscape) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(64, btScalar(1.5), 2);  // 8192 triangles, 96 x 96
    btCollisionShape* kinds[] = {shapes.box(btVector3(btScalar(0.5), btScalar(0.4), btScalar(0.6))),
                                 shapes.sphere(btScalar(0.5)), shapes.capsule(btScalar(0.3), btScalar(0.8)),
                                 shapes.hull(btVector3(btScalar(0.7), btScalar(0.5), btScalar(0.6)), 24, 7)};
    auto populate = [&](TestWorld& w) {
        w.addBody(ground, 0, btTransform::getIdentity());
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> u(-40.0, 40.0);
        for (int k = 0; k < 240; ++k)
            w.addBody(kinds[k % 4], 1,
                      btTransform(btQuaternion(btScalar(0.37 * k), btScalar(0.11 * k), 0),
                                  btVector3(btScalar(u(rng)), btScalar(4 + (k % 7)), btScalar(u(rng)))));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the convex-mesh triangle path (off by default)
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150 / kStepScale;
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 && pair.second % 4 == 0 ? double(gContactBreakingThreshold) * 1.5 : 1e-6;
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("scale: 240 objects on an 8192-triangle landscape", run);
    printRenderer(cullide);
    // Hulls on the landscape go through CULLIDE's triangle lists, and the culled pair set is never larger than
    // btDbvtBroadphase's stale superset.
    expectCulledAgreement(run, kStepScale == 1 ? 10000 : 1000);
    EXPECT_LE(run.cullideTimes.pairs, run.defaultTimes.pairs);
}

TEST(BulletScale, GImpactTorusPile) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), 0);
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(plane, 0, btTransform::getIdentity());
        for (int k = 0; k < 27; ++k) {
            const int x = k % 3, z = (k / 3) % 3, y = k / 9;
            const btQuaternion q(btVector3(1, btScalar(0.2 * x), btScalar(0.3 * z)).normalized(),
                                 btScalar(0.4 + 0.9 * k));
            w.addBody(torus, 1,
                      btTransform(q, btVector3(btScalar(1.9 * x - 1.9 + 0.2 * y), btScalar(1.5 + 1.8 * y),
                                               btScalar(1.9 * z - 1.9 - 0.15 * y))));
        }
    };
    MirrorOptions options;
    options.steps = 120 / kStepScale;
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 ? 1e-6 : 2.0 * double(gContactBreakingThreshold);
    };
    auto run = [&](bool deepPenetrationFallback) {
        TestWorld reference(PipelineKind::Default);
        TestWorld cullide(PipelineKind::Cullide);
        cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
        cullide.cullideBroadphase()->setDeepPenetrationFallback(deepPenetrationFallback);
        populate(reference);
        populate(cullide);
        const MirrorRun result = runMirrored(reference, cullide, options);
        if (deepPenetrationFallback) printRenderer(cullide);
        return result;
    };
    const MirrorRun exact = run(true);
    printMirrorRun("scale: pile of 27 GImpact tori (576 triangles each)", exact);
    expectCulledAgreement(exact, 1000 / kStepScale);
    EXPECT_LE(exact.cullideTimes.pairs, exact.defaultTimes.pairs);
    EXPECT_GT(exact.penetrationPairs, 0u) << "no tori interpenetrated: the fallback is not exercised";

    // Speed against error: the same pile with interpenetrating pairs on the culled lists too. No pair goes missing;
    // GImpact's contacts from distant triangle pairs of interpenetrating tori do.
    const MirrorRun fast = run(false);
    printMirrorRun("scale: the same pile, deep-penetration fallback off", fast);
    EXPECT_EQ(fast.agreement.missingPairs, 0u) << fast.agreement.firstMissing;
    EXPECT_EQ(fast.penetrationPairs, 0u);
}

}  // namespace
}  // namespace cullide::test
