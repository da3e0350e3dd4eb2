// GPU timings are valid or absent (issue 13): a GPU time from timer queries is reported only when the driver's result
// is available and plausible — the GPU cannot have spent longer on a span than the CPU waited for it. llvmpipe's
// first timer result in a context is an absolute time (the machine's uptime); such results must be marked absent
// (gpuTimingValid false, gpuMs 0, JSON null), never passed on.
#include "Compare.h"
#include "CullerBackends.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace cullide::test {
namespace {

/// A valid GPU time is at most the CPU wall time of the frame plus a little (clock-rate and timer granularity).
double bound(double cpuMs) { return 1.05 * cpuMs + 2.0; }

void expectValidOrAbsent(const Stats& stats, const std::string& what) {
    bool allLevelsValid = true;
    for (const LevelStats& level : stats.levels) {
        // The GL back-end's split of the level's CPU time: its set-up (of which sending) and its read-back waits
        // are parts of it. A level that drew ran on the device, so it built and sent its records first: at least
        // one record per item (every item has a primitive, every primitive at least one record).
        if (level.draws > 0) {
            EXPECT_GT(level.setupMs, 0.0) << what << ", level " << level.name;
            EXPECT_GT(level.setupSendMs, 0.0) << what << ", level " << level.name;
            EXPECT_GE(level.recordBuilds, 1u) << what << ", level " << level.name;
            EXPECT_GE(level.records, level.itemsPerIteration.front()) << what << ", level " << level.name;
        }
        EXPECT_LE(level.setupSendMs, level.setupMs) << what << ", level " << level.name;
        EXPECT_GE(level.waitMs, 0.0) << what << ", level " << level.name;
        EXPECT_LE(level.setupMs + level.waitMs, level.cpuMs) << what << ", level " << level.name;
        if (level.gpuTimingValid) {
            EXPECT_GE(level.gpuMs, 0.0) << what << ", level " << level.name;
            EXPECT_GE(level.exactGpuMs, 0.0) << what << ", level " << level.name;
            EXPECT_LE(level.exactGpuMs, level.gpuMs) << what << ", level " << level.name << ": a part of it";
            // A deferred level's or a level run ahead's device work may run while later levels are issued and in
            // the wait that another level counts: the frame's time bounds it.
            if (level.blockingReadBacks > 0 && !level.deferred) {
                EXPECT_LE(level.gpuMs, bound(level.cpuMs)) << what << ", level " << level.name;
            }
            EXPECT_LE(level.gpuMs, bound(stats.totalMs)) << what << ", level " << level.name;
        } else {
            EXPECT_EQ(level.gpuMs, 0.0) << what << ", level " << level.name << ": an absent time must not read as one";
            EXPECT_EQ(level.exactGpuMs, 0.0) << what << ", level " << level.name;
            allLevelsValid = false;
        }
    }
    EXPECT_EQ(stats.gpuTimingValid, allLevelsValid) << what;
    // Each device exact stage is timed by a span of its own, counted in the level it followed: where the device found
    // pairs it did work, and its time shows.
    double exactMs = 0.0;
    for (const LevelStats& level : stats.levels) exactMs += level.exactGpuMs;
    if (stats.gpuTimingValid && stats.deviceExactPairs > 0) {
        EXPECT_GT(exactMs, 0.0) << what;
    }
    if (stats.gpuTimingValid) {
        EXPECT_GE(stats.gpuMs, 0.0) << what;
        EXPECT_LE(stats.gpuMs, bound(stats.totalMs)) << what;
        // The uploads are part of it, timed apart: where levels ran, an upload did (and built group boxes here).
        EXPECT_LE(stats.uploadGpuMs, stats.gpuMs) << what;
        if (!stats.levels.empty()) {
            EXPECT_GT(stats.uploadGpuMs, 0.0) << what;
        }
    } else {
        EXPECT_EQ(stats.gpuMs, 0.0) << what;
        EXPECT_EQ(stats.uploadGpuMs, 0.0) << what;
    }
}

TEST(GpuTiming, ReportedTimesAreValidOrAbsent) {
    const auto meshes = randomSoups(11, 40, 100, 0.08);
    const auto objects = asObjects(meshes);
    for (Backend backend : {Backend::Compute, Backend::Raster}) {
        for (Pipeline pipeline : {Pipeline::Auto, Pipeline::Paper}) {
            Settings settings;
            settings.gpuLevels = GpuLevels::Always;  // GPU levels also on llvmpipe
            settings.exactThreshold = 0;
            settings.resolution = 64;
            settings.backend = backend;
            settings.pipeline = pipeline;
            settings.deviceExact = DeviceExact::Always;  // after each deferred triangle level (the Auto pipeline's)
            CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
            std::size_t exactTimedFrames = 0;  // frames whose device exact stage found pairs, with valid timings
            for (int frame = 0; frame < 3; ++frame) {
                Result result;
                culler->run(objects, result);
                const std::string what = std::string(backend == Backend::Compute ? "compute" : "raster") +
                                         (pipeline == Pipeline::Auto ? " auto" : " paper") + " frame " +
                                         std::to_string(frame) + " (" + result.stats.renderer + ")";
                ASSERT_FALSE(result.stats.levels.empty()) << what << ": the GPU levels must run in this test";
                if (result.stats.gpuTimingValid && result.stats.deviceExactPairs > 0) ++exactTimedFrames;
                EXPECT_EQ(result.stats.gpuFallbacks, 0u) << what << ": " << result.stats.gpuError;
                expectValidOrAbsent(result.stats, what);
            }
            if (pipeline == Pipeline::Auto) {
                EXPECT_GT(exactTimedFrames, 0u) << "the device exact stage's timing must be checked in some frame";
            }
        }
    }
}

/// A level runs on the device as one chain per record build: its set-up never waits (the builds, at the level's start
/// and at a refit of its bands, are dispatched indirectly and never read back), nor do its iterations (each one's last
/// work group starts the next); a level waited for blocks once at the end of each chain, a read-back that brings the
/// alive set too. The group level is not waited for at all: the triangle level inherits its survivors on the device,
/// and its read-back brings the group level's chain. The triangle level of each cluster is deferred: the frame reads
/// them all back at once, one read-back whichever cluster counts it, unless its place stopped early last time (a
/// refit): then it is waited for at once. In a steady frame (the second) a level issues as many iterations as it ran
/// before: no chain ends early, no level runs again.
/// Every read-back here waits 60 ms more, inside the timed wait: a set-up that waited for one read-back would reach
/// 60 ms, against ~1 ms of its own work on llvmpipe once the shaders are compiled (the first frame, untimed here,
/// compiles them).
TEST(GpuTiming, OnlyTheEndOfEachChainOfIterationsIsWaitedFor) {
    constexpr double kDelayMs = 60.0;
    const auto meshes = randomSoups(11, 40, 100, 0.08);  // the objects point into them
    const auto objects = asObjects(meshes);
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;
    settings.exactThreshold = 0;
    settings.resolution = 64;
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    GlBackendOptions options;
    options.readBackDelayMs = kDelayMs;
    std::unique_ptr<Culler> culler =
        createGpuCuller(settings, [options](const Settings& s) { return createGlPruningBackend(s, options); });
    Result result;
    culler->run(objects, result);  // warm-up: shader compilation, buffer growth
    culler->run(objects, result);
    EXPECT_EQ(result.stats.gpuFallbacks, 0u) << result.stats.gpuError;
    EXPECT_EQ(result.stats.levelReruns, 0u);
    std::size_t levelsRun = 0, refits = 0, readBacks = 0, severalIterations = 0, groupsAhead = 0, deferred = 0;
    std::size_t deferredReadBacks = 0;
    for (const LevelStats& level : result.stats.levels) {
        if (level.draws == 0) continue;  // a level with nothing to prune never reaches the device
        ++levelsRun;
        EXPECT_GE(level.recordBuilds, 1u) << level.name;
        if (level.recordBuilds > 1) refits += level.recordBuilds - 1;
        if (level.iterations > 1) ++severalIterations;
        readBacks += level.blockingReadBacks;
        if (level.deferred) {
            ++deferred;
            deferredReadBacks += level.blockingReadBacks;
        } else if (level.name == "groups" && level.blockingReadBacks == 0) {
            ++groupsAhead;
        } else {
            // One read-back per chain, and a chain per record build: a build is never waited for, a refit's
            // included, nor is an iteration: all of the waiting is in those read-backs.
            EXPECT_EQ(level.blockingReadBacks, level.recordBuilds) << level.name << ": a read-back besides the chains'";
        }
        // Issued as many as the level ran last frame; a refit stops the chain, so the iterations issued after it
        // wait for the next chain.
        if (level.recordBuilds == 1) {
            EXPECT_EQ(level.idleIterations, 0u) << level.name << ": the level issued more than it ran last frame";
        }
        EXPECT_GE(level.waitMs, kDelayMs * static_cast<double>(level.blockingReadBacks)) << level.name;
        EXPECT_LT(level.setupMs, kDelayMs) << level.name << ": the set-up counted a read-back";
        EXPECT_LE(level.setupMs + level.waitMs, level.cpuMs) << level.name;
    }
    EXPECT_GE(levelsRun, 2u) << "the scene must take the GPU levels to the device";
    EXPECT_GE(refits, 1u) << "the scene must refit some level's bands (the second set-up path)";
    EXPECT_GE(severalIterations, 1u) << "the scene must run a level of several iterations (a chain)";
    EXPECT_GE(groupsAhead, 1u) << "a group level must run ahead of its triangle level";
    EXPECT_GE(deferred, 2u) << "the scene must defer the triangle levels of several clusters";
    EXPECT_EQ(deferredReadBacks, 1u) << "the deferred levels share one read-back";
    EXPECT_EQ(result.stats.blockingReadBacks, readBacks);
}

TEST(GpuTiming, FramesWithoutGpuLevelsReportZeroAsValid) {
    Settings settings;
    settings.gpuLevels = GpuLevels::Never;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    const auto meshes = randomSoups(12, 10, 40, 0.3);
    Result result;
    culler->run(asObjects(meshes), result);
    EXPECT_TRUE(result.stats.levels.empty());
    EXPECT_TRUE(result.stats.gpuTimingValid);
    EXPECT_EQ(result.stats.gpuMs, 0.0);
}

/// cullide-pairs prints a GPU time only where it is valid: a number no larger than the frame, else null.
TEST(GpuTiming, CullidePairsPrintsNullOrAPlausibleTime) {
    {
        Settings demanding;  // Settings{} (GpuLevels::Auto) would run without GL: the probe must demand it
        demanding.gpuLevels = GpuLevels::Always;
        CULLIDE_GPU_CULLER_OR_SKIP(probe, demanding);  // GL policy: skip outside CI only
    }
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("cullide_gpu_timing_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "a.off") << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::ofstream(dir / "b.off") << "OFF\n3 1 0\n0.2 0.2 -0.5\n0.2 0.2 0.5\n0.9 0.9 0\n3 0 1 2\n";
    std::ofstream(dir / "scene.json") << "{\"objects\": [{\"mesh\": \"a.off\"}, {\"mesh\": \"b.off\"}]}";
    for (const char* backend : {"compute", "raster"}) {
        const std::string command = std::string(CULLIDE_PAIRS_EXE) + " " + (dir / "scene.json").string() +
                                    " --gpu-levels always --pipeline paper --resolution 64 --backend " + backend +
                                    " > " + (dir / "out.json").string();
        const int raw = std::system(command.c_str());
        ASSERT_TRUE(WIFEXITED(raw) && WEXITSTATUS(raw) == 0) << command;
        std::ifstream in(dir / "out.json");
        std::stringstream text;
        text << in.rdbuf();
        const auto stats = nlohmann::json::parse(text.str())["stats"];
        const double total = stats["total_ms"].get<double>();
        ASSERT_FALSE(stats["levels"].empty()) << text.str();
        for (const auto& level : stats["levels"]) {
            ASSERT_TRUE(level["gpu_ms"].is_null() || level["gpu_ms"].is_number()) << level.dump();
            if (level["gpu_ms"].is_number()) {
                EXPECT_LE(level["gpu_ms"].get<double>(), bound(total)) << level.dump();
            }
        }
        ASSERT_TRUE(stats["gpu_ms"].is_null() || stats["gpu_ms"].is_number()) << stats.dump();
        if (stats["gpu_ms"].is_number()) {
            EXPECT_LE(stats["gpu_ms"].get<double>(), bound(total)) << stats.dump();
        }
    }
    fs::remove_all(dir);
}

}  // namespace
}  // namespace cullide::test
