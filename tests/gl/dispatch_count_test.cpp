// What a level costs in draws and dispatches (Stats::draws, LevelStats::draws) in a steady frame: the Auto pipeline's
// levels, described by their objects, start with one dispatch (start.comp: their items and first view); the record
// build is one dispatch, where the pixels per band are a constant (long bands on a software renderer; the raster
// back-end has no bands) and where short bands take them from the last build in the level's place (only a place's
// first build sums every primitive's footprint first: FOOTPRINTS, then APPEND); each iteration issued is its three
// passes on the compute back-end (the flag pass ends it), and on the raster back-end a set-up dispatch, the three
// draws and the survivor pass; a deferred triangle level is followed by the device exact stage, one dispatch
// (exact.comp). Nothing else is dispatched but, per cluster, the dispatch that builds its group boxes
// (group_boxes.comp: these meshes are not static; they come without transforms, so map.comp has none).
#include "Compare.h"
#include "CullerBackends.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>

namespace cullide::test {
namespace {

struct Case {
    const char* name;
    Backend backend;
    bool shortBands;
};

/// Dispatches per record build and per iteration issued for a case, in a steady frame.
std::pair<std::size_t, std::size_t> costs(const Case& c) {
    if (c.backend == Backend::Raster) return {1, 5};
    return {1, 3};
}

TEST(DispatchCount, ABuildIsOneDispatchInASteadyFrameAndAComputeIterationThree) {
    const auto meshes = randomSoups(11, 40, 100, 0.08);
    const auto objects = asObjects(meshes);
    for (const Case& c : {Case{"compute", Backend::Compute, false}, Case{"compute, short bands", Backend::Compute, true},
                          Case{"raster", Backend::Raster, false}}) {
        Settings settings;
        settings.gpuLevels = GpuLevels::Always;
        settings.deviceExact = DeviceExact::Always;
        settings.exactThreshold = 0;
        settings.resolution = 64;
        settings.backend = c.backend;
        CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
        GlBackendOptions options;
        options.shortBands = c.shortBands;
        auto culler =
            createGpuCuller(settings, [options](const Settings& s) { return createGlPruningBackend(s, options); });
        Result r;
        for (int frame = 0; frame < 3; ++frame) culler->run(objects, r);  // steady: no short build, no rerun
        ASSERT_EQ(r.stats.gpuFallbacks, 0u) << c.name << ": " << r.stats.gpuError;
        const auto [perBuild, perIteration] = costs(c);
        std::size_t levelDraws = 0, levelsRun = 0;
        for (const LevelStats& level : r.stats.levels) {
            levelDraws += level.draws;
            if (level.draws == 0) continue;  // ended on the CPU
            ++levelsRun;
            EXPECT_EQ(level.shortBuilds, 0u) << c.name << ", " << level.name;
            const std::size_t issued = level.iterations + level.idleIterations;
            const std::size_t exactStage = level.deferred ? 1 : 0;
            EXPECT_EQ(level.draws, 1 + level.recordBuilds * perBuild + issued * perIteration + exactStage)
                << c.name << ", " << level.name << ": " << level.recordBuilds << " builds, " << level.iterations
                << " iterations + " << level.idleIterations << " idle";
        }
        EXPECT_GE(levelsRun, 2u) << c.name;
        EXPECT_GE(r.stats.clusters, 2u) << c.name;
        std::size_t deferred = 0;
        for (const LevelStats& level : r.stats.levels) deferred += level.deferred ? 1 : 0;
        EXPECT_GE(deferred, 1u) << c.name;
        EXPECT_EQ(r.stats.deviceExactClusters, deferred) << c.name << ": a deferred level without the exact stage";
        EXPECT_EQ(r.stats.draws, levelDraws + r.stats.clusters) << c.name << ": a dispatch outside the levels";
    }
}

}  // namespace
}  // namespace cullide::test
