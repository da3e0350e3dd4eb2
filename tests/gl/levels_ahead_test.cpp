// The group level run ahead of the triangle level (never waited for): a frame whose group level needs more iterations
// than the levels in its place ran before finds out only at the triangle level's read-back. Both levels then run again,
// the group level waited for, and the frame keeps exactly what the reference keeps; the next frame waits for it too,
// and once it has run as one chain the group level runs ahead again. Held to the visibility reference
// (VisibilityLockstep) and to the exact reference culler.
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"

#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace cullide::test {
namespace {

const LevelStats* levelNamed(const Result& r, const std::string& name) {
    for (const LevelStats& level : r.stats.levels)
        if (level.name == name) return &level;
    return nullptr;
}

TEST(LevelsAhead, AGroupLevelThatNeedsMoreIterationsRunsAgainWaitedFor) {
    Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    settings.minPruneFraction = 0.0;  // a level goes on while its set changes
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    // Frame 0, two tori on top of each other: every group is hidden by the other torus's, so the group level's first
    // iteration prunes nothing and ends it. Then the paper's deforming tori (env2): the group level goes on past its
    // first iteration.
    const TriangleMesh torus = scenes::makeTorus(1.0, 0.25, 48, 16);
    const std::vector<TriangleMesh> tori = scenes::makeEnv2(1)->frame(3);
    const std::vector<std::vector<TriangleMesh>> frames = {{torus, torus}, tori, tori, tori};
    std::vector<Result> results(frames.size());
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const Comparison c = runAndCompare(*culler, *reference, asObjects(frames[f]), results[f]);
        EXPECT_EQ(results[f].stats.gpuFallbacks, 0u) << "frame " << f << ": " << results[f].stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << f << ": " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << "frame " << f;
        ASSERT_NE(levelNamed(results[f], "groups"), nullptr) << "frame " << f;
        ASSERT_NE(levelNamed(results[f], "triangles"), nullptr) << "frame " << f;
    }
    EXPECT_EQ(levelNamed(results[0], "groups")->iterations, 1u);
    const LevelStats& groups = *levelNamed(results[1], "groups");
    EXPECT_GE(groups.iterations, 2u) << "the scene must make the group level go on: " << groups.itemsPerIteration.front()
                                     << " -> " << groups.itemsPerIteration.back();
    // Frame 1: issued one iteration (what frame 0 ran), needed more: run again, waited for.
    EXPECT_EQ(results[1].stats.levelReruns, 1u);
    EXPECT_GE(levelNamed(results[1], "groups")->blockingReadBacks, 1u);
    // Frame 2: waited for again (the place stopped early last time), as one chain now.
    EXPECT_EQ(results[2].stats.levelReruns, 0u);
    EXPECT_EQ(levelNamed(results[2], "groups")->blockingReadBacks, 1u);
    // Frame 3: ahead again, one read-back for the frame.
    EXPECT_EQ(results[3].stats.levelReruns, 0u);
    EXPECT_EQ(levelNamed(results[3], "groups")->blockingReadBacks, 0u);
    EXPECT_EQ(results[3].stats.blockingReadBacks, 1u);
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GE(log->levelsAhead, 2u) << log->summary();
}

}  // namespace
}  // namespace cullide::test
