// The GL visibility test against its CPU reference on the paper's environments (frame 3) at 64², both pipelines,
// both modes (VisibilityLockstep): the GL levels prune exactly what the pruning-strength tests measure.
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <ostream>
#include <string>
#include <vector>

namespace cullide::test {
namespace {

/// The paper's environments (frame 3) at 64², both pipelines, both modes: the same check on the scenes the
/// pruning-strength tests (unit, reference backend) measure, so that the GL levels prune exactly that much.
struct EnvironmentCase {
    const char* scene;
    LockstepCase settings;
};

void PrintTo(const EnvironmentCase& c, std::ostream* os) { *os << c.scene << lockstepName(c.settings); }

class EnvironmentLockstep : public ::testing::TestWithParam<EnvironmentCase> {};

TEST_P(EnvironmentLockstep, GlKeepsExactlyWhatTheReferenceKeeps) {
    const EnvironmentCase c = GetParam();
    const Settings settings = lockstepSettings(c.settings);
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    const std::string scene = c.scene;
    std::vector<std::vector<TriangleMesh>> frames;
    if (scene == "env1") frames.push_back(scenes::makeEnv1(1)->frame(3));
    if (scene == "env2") frames.push_back(scenes::makeEnv2(1)->frame(3));
    if (scene == "env3") frames.push_back(scenes::makeEnv3(scenes::defaultDataDir(), false)->frame(3));
    const LockstepLog log = runInLockstep(settings, frames);
    EXPECT_EQ(log.mismatches, 0u) << log.summary();
    EXPECT_GT(log.itemsPruned, log.itemsIn / 10) << log.summary();
}

std::vector<EnvironmentCase> environmentCases() {
    std::vector<EnvironmentCase> cases;
    for (const char* scene : {"env1", "env2", "env3"})
        for (Pipeline pipeline : {Pipeline::Auto, Pipeline::Paper})
            for (Mode mode : {Mode::Reliable, Mode::Sampled})
                cases.push_back({scene, {pipeline, mode, Backend::Compute, 64}});
    cases.push_back({"env1", {Pipeline::Paper, Mode::Reliable, Backend::Raster, 64}});
    return cases;
}

std::string environmentCaseName(const ::testing::TestParamInfo<EnvironmentCase>& param) {
    return std::string(param.param.scene) + lockstepName(param.param.settings);
}

INSTANTIATE_TEST_SUITE_P(Frames, EnvironmentLockstep, ::testing::ValuesIn(environmentCases()), environmentCaseName);

}  // namespace
}  // namespace cullide::test
