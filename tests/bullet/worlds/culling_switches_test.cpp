// The broadphase's culling switches in worlds (CullideBroadphase.h: Culling, CulledKind). The default, Auto: on a
// machine without a hardware GL device it culls nothing, makes no culler, and the world stays bit for bit Bullet's
// default pipeline; trialled (setAutoCullingOnAnyDevice), it decides on the running scene and loses no contact
// while it measures. On and Off, and the bool setters.
#include "SceneSupport.h"
#include "cullide/Culler.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <vector>

namespace cullide::test {
namespace {

const CulledKind kKinds[] = {CulledKind::GImpactPair, CulledKind::GImpactMesh, CulledKind::GImpactConvex,
                             CulledKind::ConvexMesh};

/// A pile of GImpact tori on a ground box: GImpact pairs of two kinds (GImpact-GImpact, GImpact-convex).
void populate(TestWorld& w, ShapeStore& shapes) {
    btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
    w.addBody(shapes.box(btVector3(8, 1, 8)), 0, btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)));
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.02));
    for (int k = 0; k < 12; ++k)
        w.addBody(torus, 1,
                  btTransform(btQuaternion(btVector3(1, btScalar(0.3 * k), 0).normalized(), btScalar(0.5 * k)),
                              btVector3(btScalar(1.1 * (k % 3) - 1.1), btScalar(0.6 + 0.7 * k), btScalar(0.4 * (k % 2)))));
}

TEST(CullingSwitches, TheSettersAndWhatTheyReport) {
    CullideBroadphase bp(Settings{}, nullptr, referenceFactory());
    for (const CulledKind k : kKinds) {
        EXPECT_EQ(bp.getCulling(k), Culling::Auto) << int(k);  // the default
        EXPECT_FALSE(bp.isCulled(k)) << int(k);               // nothing decided yet
    }
    bp.setGImpactPairCulling(true);
    EXPECT_EQ(bp.getCulling(CulledKind::GImpactPair), Culling::On);
    EXPECT_TRUE(bp.getGImpactPairCulling());
    EXPECT_TRUE(bp.mayCull(CulledKind::GImpactPair));
    EXPECT_EQ(bp.getCullingDecision(CulledKind::GImpactPair).state, "culled");
    bp.setGImpactPairCulling(false);
    EXPECT_EQ(bp.getCulling(CulledKind::GImpactPair), Culling::Off);
    EXPECT_FALSE(bp.getGImpactPairCulling());
    EXPECT_FALSE(bp.mayCull(CulledKind::GImpactPair));
    EXPECT_EQ(bp.getCullingDecision(CulledKind::GImpactPair).state, "not culled");
    bp.setConvexMeshCulling(Culling::On);
    EXPECT_TRUE(bp.getConvexMeshCulling());
    if (!hasHardwareGlDevice()) {
        EXPECT_FALSE(bp.mayCull(CulledKind::GImpactMesh));  // Auto: never trialled here
        EXPECT_EQ(bp.getCullingDecision(CulledKind::GImpactMesh).state, "not trialled");
    }
    bp.setAutoCullingOnAnyDevice(true);
    EXPECT_TRUE(bp.mayCull(CulledKind::GImpactMesh));
    EXPECT_EQ(bp.getCullingDecision(CulledKind::GImpactMesh).state, "waiting");
}

TEST(CullingSwitches, AutoWithoutAHardwareDeviceMakesNoCullerAndStaysBulletsPipeline) {
    if (hasHardwareGlDevice()) GTEST_SKIP() << "a hardware GL device: Auto trials here";
    ShapeStore shapes;
    TestWorld off(PipelineKind::Cullide), byDefault(PipelineKind::Cullide);
    for (const CulledKind k : kKinds) off.cullideBroadphase()->setCulling(k, Culling::Off);
    populate(off, shapes);
    populate(byDefault, shapes);
    EXPECT_EQ(firstDifferingStep(off, byDefault, 90), -1) << "Auto must cull nothing here";
    const CullideBroadphase& bp = *byDefault.cullideBroadphase();
    EXPECT_EQ(bp.getCullingMargin(), 0.0) << "no culler made";
    EXPECT_EQ(bp.getLastFrameStats().culledPairs, 0u);
    for (const CulledKind k : kKinds) EXPECT_EQ(bp.getCullingDecision(k).state, "not trialled");
}

// (What a trial step costs against the steps around it is a figure, not an assertion: cullide-trial-bench; the
// ramp and budget that bound it are AutoCulling's unit tests.)
TEST(CullingSwitches, AutoTrialledDecidesAndLosesNoContact) {
    ShapeStore shapes;
    TestWorld reference(PipelineKind::Default), automatic(PipelineKind::Cullide, referenceFactory());
    automatic.cullideBroadphase()->setAutoCullingOnAnyDevice(true);
    populate(reference, shapes);
    populate(automatic, shapes);
    MirrorOptions options;
    // Auto's culler is made on another thread and no step waits for it: on a loaded machine the trials start late
    // (a trial step before it is ready is cancelled), so the world runs long enough for both kinds' trials to end.
    options.steps = 240;
    options.tolerance = [](const std::pair<int, int>&) { return 1e30; };  // culled steps place points otherwise
    std::size_t culledSteps = 0;
    const std::array<CulledKind, 2> trialled = {CulledKind::GImpactPair, CulledKind::GImpactConvex};
    std::vector<CullingDecision> decided;  // both kinds' decisions, as at the first step both were decided
    options.each = [&](int, TestWorld&, TestWorld& w) {
        const CullideBroadphase& bp = *w.cullideBroadphase();
        culledSteps += bp.getLastFrameStats().culledPairs > 0 ? 1 : 0;
        if (!decided.empty()) return;
        std::vector<CullingDecision> now;
        for (const CulledKind k : trialled) now.push_back(bp.getCullingDecision(k));
        const auto isDecided = [](const CullingDecision& d) { return d.state == "on" || d.state == "off"; };
        if (std::all_of(now.begin(), now.end(), isDecided)) decided = now;
    };
    const MirrorRun run = runMirrored(reference, automatic, options);
    EXPECT_EQ(run.agreement.missingPairs, 0u) << run.agreement.firstMissing;  // no contact lost, trial or not
    EXPECT_GT(run.agreement.referencePairs, 100u);
    EXPECT_GT(culledSteps, 0u) << "the trials cull";
    const CullideBroadphase& bp = *automatic.cullideBroadphase();
    ASSERT_EQ(decided.size(), trialled.size()) << "both kinds' trials must end within " << options.steps << " steps";
    for (std::size_t i = 0; i < trialled.size(); ++i) {
        const int k = static_cast<int>(trialled[i]);
        const CullingDecision& d = decided[i];
        EXPECT_TRUE(d.state == "on" || d.state == "off") << k << ": " << d.state;
        EXPECT_GT(d.unculledMs, 0.0) << k;
        EXPECT_GT(d.culledMs, 0.0) << k;
        EXPECT_EQ(d.culled, d.state == "on") << k;
    }
    // No kind of pair without pairs is trialled.
    EXPECT_EQ(bp.getCullingDecision(CulledKind::GImpactMesh).state, "waiting");
    EXPECT_EQ(bp.getCullingDecision(CulledKind::ConvexMesh).state, "waiting");
}

}  // namespace
}  // namespace cullide::test
