// The GL visibility test keeps what its CPU reference keeps when triangles are split into bands: large triangles at
// 512², and the short bands of a hardware GPU built and run on this device (VisibilityLockstep).
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"

#include <gtest/gtest.h>

#include <memory>

namespace cullide::test {
namespace {

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

}  // namespace
}  // namespace cullide::test
