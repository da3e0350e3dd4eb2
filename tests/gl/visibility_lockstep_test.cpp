// The GL visibility test against its CPU reference (ReferenceVisibility): at small resolutions the GPU levels keep
// exactly the items the reference keeps, iteration by iteration, level by level, in both pipelines, both modes and
// both back-ends (VisibilityLockstep compares every iteration of whole culling frames).
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace cullide::test {
namespace {

std::string caseName(const ::testing::TestParamInfo<LockstepCase>& info) { return lockstepName(info.param); }

class VisibilityLockstep : public ::testing::TestWithParam<LockstepCase> {};

TEST_P(VisibilityLockstep, GlKeepsExactlyWhatTheReferenceKeeps) {
    const Settings settings = lockstepSettings(GetParam());
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    std::vector<std::vector<TriangleMesh>> frames;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) frames.push_back(randomSoups(seed, 12, 60, 0.2));
    scenes::RandomSceneOptions options;
    options.objects = 12;
    frames.push_back(scenes::makeRandomScene(5, options));  // closed shapes, open meshes and soups
    const LockstepLog log = runInLockstep(settings, frames);
    EXPECT_EQ(log.mismatches, 0u) << log.summary();
    // The comparison saw real work: several iterations, and items pruned by them.
    EXPECT_GE(log.iterations, 8u) << log.summary();
    EXPECT_GT(log.itemsPruned, log.itemsIn / 10) << log.summary();
}

INSTANTIATE_TEST_SUITE_P(
    Matrix, VisibilityLockstep,
    ::testing::Values(LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Compute, 16},
                      LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Compute, 64},
                      LockstepCase{Pipeline::Auto, Mode::Sampled, Backend::Compute, 16},
                      LockstepCase{Pipeline::Auto, Mode::Sampled, Backend::Compute, 64},
                      LockstepCase{Pipeline::Paper, Mode::Reliable, Backend::Compute, 16},
                      LockstepCase{Pipeline::Paper, Mode::Reliable, Backend::Compute, 64},
                      LockstepCase{Pipeline::Paper, Mode::Sampled, Backend::Compute, 16},
                      LockstepCase{Pipeline::Paper, Mode::Sampled, Backend::Compute, 64},
                      LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Raster, 16},
                      LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Raster, 64},
                      LockstepCase{Pipeline::Auto, Mode::Sampled, Backend::Raster, 16},
                      LockstepCase{Pipeline::Auto, Mode::Sampled, Backend::Raster, 64},
                      LockstepCase{Pipeline::Paper, Mode::Reliable, Backend::Raster, 16},
                      LockstepCase{Pipeline::Paper, Mode::Reliable, Backend::Raster, 64},
                      LockstepCase{Pipeline::Paper, Mode::Sampled, Backend::Raster, 16},
                      LockstepCase{Pipeline::Paper, Mode::Sampled, Backend::Raster, 64},
                      // Fewer views: an item is done after fewer invocations (flag.comp's count per item).
                      LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Compute, 64, 5},
                      LockstepCase{Pipeline::Paper, Mode::Sampled, Backend::Compute, 16, 2},
                      LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Raster, 64, 5},
                      // A margin: boxes grown by it (the built group boxes' growth, group_boxes.comp), views fitted
                      // with it.
                      LockstepCase{Pipeline::Auto, Mode::Reliable, Backend::Compute, 64, 7, 0.01},
                      LockstepCase{Pipeline::Paper, Mode::Reliable, Backend::Raster, 16, 7, 0.01}),
    caseName);

}  // namespace
}  // namespace cullide::test
