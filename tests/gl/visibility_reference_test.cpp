// The GL visibility test against its CPU reference (ReferenceVisibility): at small resolutions the GPU levels keep
// exactly the items the reference keeps, iteration by iteration, level by level, in both pipelines, both modes and
// both back-ends (VisibilityLockstep compares every iteration of whole culling frames).
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <memory>
#include <ostream>
#include <string>

namespace cullide::test {
namespace {

struct LockstepCase {
    Pipeline pipeline;
    Mode mode;
    Backend backend;
    int resolution;
};

std::string name(const LockstepCase& c) {
    return std::string(c.pipeline == Pipeline::Paper ? "Paper" : "Auto") +
           (c.mode == Mode::Reliable ? "Reliable" : "Sampled") + (c.backend == Backend::Raster ? "Raster" : "Compute") +
           std::to_string(c.resolution);
}
std::string caseName(const ::testing::TestParamInfo<LockstepCase>& info) { return name(info.param); }
void PrintTo(const LockstepCase& c, std::ostream* os) { *os << name(c); }

Settings lockstepSettings(const LockstepCase& c) {
    Settings s;
    s.pipeline = c.pipeline;
    s.mode = c.mode;
    s.backend = c.backend;
    s.resolution = c.resolution;
    s.gpuLevels = GpuLevels::Always;
    s.exactThreshold = 0;  // every level runs
    s.threads = 2;
    return s;
}

/// Runs `frames` through a culler whose GL backend is checked against the reference; returns the comparison. The
/// caller has already made sure a GL device is there (CULLIDE_GPU_CULLER_OR_SKIP).
LockstepLog runInLockstep(const Settings& settings, const std::vector<std::vector<TriangleMesh>>& frames) {
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    for (const std::vector<TriangleMesh>& meshes : frames) {
        Result r;
        culler->run(asObjects(meshes), r);
        EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
    }
    return *log;
}

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

/// Two crossing quads, each two triangles wider than half the view: at 512² each triangle covers more pixels of
/// its views than one compute invocation may scan (CULLIDE_MAX_LOOP_ITERATIONS), so its records must be bands. A
/// band count from too small a footprint shows as an overflow, which the lockstep check counts as a mismatch.
TEST(VisibilityBands, LargeTrianglesAreSplitIntoBandsAndKeptAsTheReferenceKeepsThem) {
    const Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 512});
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    TriangleMesh flat, upright;
    flat.vertices = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    upright.vertices = {{0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1}};
    flat.triangles = upright.triangles = {{0, 1, 2}, {0, 2, 3}};
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    Result r;
    culler->run(asObjects({flat, upright}), r);
    EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    bool sawTriangles = false;
    for (const LevelStats& level : r.stats.levels) {
        if (level.name != "triangles") continue;
        sawTriangles = true;
        EXPECT_GT(level.records, 4 * level.itemsPerIteration.front()) << "too few bands for the quads' triangles";
    }
    EXPECT_TRUE(sawTriangles);
    EXPECT_EQ(r.pairs.size(), 1u);
}

/// The records a hardware GPU builds (bands of about 32 pixels: many records per primitive), built and run on this
/// device, which otherwise makes one 4,096-pixel band of each: the band arithmetic of the record build, its sums
/// over many records per primitive and the passes over bands run here as on a GPU. Both pipelines: the paper's
/// items of whole objects and of groups have many primitives each.
TEST(VisibilityBands, ShortBandsAsOnAGpuKeepWhatTheReferenceKeeps) {
    for (const Pipeline pipeline : {Pipeline::Auto, Pipeline::Paper}) {
        const Settings settings = lockstepSettings({pipeline, Mode::Reliable, Backend::Compute, 256});
        CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
        auto log = std::make_shared<LockstepLog>();
        GlBackendOptions options;
        options.shortBands = true;
        std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log, options));
        std::size_t records = 0, items = 0;
        for (std::uint64_t seed = 1; seed <= 2; ++seed) {
            Result r;
            culler->run(asObjects(randomSoups(seed, 12, 60, 0.2)), r);
            EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
            for (const LevelStats& level : r.stats.levels) {
                records += level.records;
                items += level.itemsPerIteration.front();
            }
        }
        EXPECT_EQ(log->mismatches, 0u) << log->summary();
        EXPECT_GE(log->iterations, 4u) << log->summary();
        EXPECT_GT(log->itemsPruned, 0u) << log->summary();
        EXPECT_GT(records, 8 * items) << "bands as long as on llvmpipe";
    }
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
                      LockstepCase{Pipeline::Paper, Mode::Sampled, Backend::Raster, 64}),
    caseName);

/// The paper's environments (frame 3) at 64², both pipelines, both modes: the same check on the scenes the
/// pruning-strength tests (unit, reference backend) measure, so that the GL levels prune exactly that much.
struct EnvironmentCase {
    const char* scene;
    LockstepCase settings;
};

void PrintTo(const EnvironmentCase& c, std::ostream* os) { *os << c.scene << name(c.settings); }

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
    return std::string(param.param.scene) + name(param.param.settings);
}

INSTANTIATE_TEST_SUITE_P(Frames, EnvironmentLockstep, ::testing::ValuesIn(environmentCases()), environmentCaseName);

}  // namespace
}  // namespace cullide::test
