// A frame of several clusters waits once: each cluster's triangle level is issued and deferred, and the frame reads
// them all back together (PruningBackend::collect). A cluster whose chain stopped early on the device (records to
// build again, more iterations needed than were issued) runs again, waited for, in its place: its levels replace the
// first attempt's in the frame's stats, in cluster order. Held to the visibility reference (VisibilityLockstep: every
// deferred level's trace and survivors), to the CPU visibility reference's levels, and to the exact reference culler.
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"

#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

namespace cullide::test {
namespace {

/// Three sets of the paper's deforming tori (env2) far apart: three clusters of different sizes, deforming from frame
/// to frame, each moved along y by `shift`.
std::vector<TriangleMesh> threeClusters(int frame, int triangles = 1500, double shift = 0.0) {
    std::vector<TriangleMesh> meshes;
    for (int c = 0; c < 3; ++c) {
        std::vector<TriangleMesh> tori = scenes::makeEnv2(1 + c, 3 + c, triangles + triangles / 3 * c)->frame(3 + frame);
        for (TriangleMesh& m : tori) {
            for (Vec3& p : m.vertices) p += Vec3(20.0 * c, shift, 0.0);
            meshes.push_back(std::move(m));
        }
    }
    return meshes;
}

/// The frame's levels as run: each one's read-backs, builds and iterations (failure messages).
std::string levelCosts(const Stats& stats) {
    std::string s;
    for (const LevelStats& l : stats.levels)
        s += " [" + l.name + (l.deferred ? " deferred" : "") + ": " + std::to_string(l.blockingReadBacks) +
             " read-backs, " + std::to_string(l.recordBuilds) + " builds (" + std::to_string(l.shortBuilds) +
             " short), " + std::to_string(l.iterations) + " iterations + " + std::to_string(l.idleIterations) +
             " idle]";
    return s;
}

std::size_t deferredLevels(const Stats& stats) {
    std::size_t n = 0;
    for (const LevelStats& level : stats.levels) n += level.deferred ? 1 : 0;
    return n;
}

/// The frame's levels as the CPU visibility reference runs them (one cluster after the other, nothing deferred): each
/// one's name and items per iteration.
std::vector<std::string> levelOutline(const Stats& stats) {
    std::vector<std::string> outline;
    for (const LevelStats& level : stats.levels) {
        std::string s = level.name + ":";
        for (std::size_t n : level.itemsPerIteration) s += " " + std::to_string(n);
        outline.push_back(s);
    }
    return outline;
}

TEST(DeferredLevels, AFrameOfSeveralClustersWaitsOnceAndKeepsWhatTheReferenceKeeps) {
    const Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> visibility = createVisibilityReferenceCuller(settings);
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    // Four frames deforming (a level whose place needs more iterations than before runs again, waited for, and the
    // next frame waits for it too), then four in which the clusters only move: by the last two every place knows
    // its iterations.
    constexpr int kDeforming = 4, kFrames = 8;
    std::size_t reruns = 0;
    for (int f = 0; f < kFrames; ++f) {
        const std::vector<TriangleMesh> meshes =
            f < kDeforming ? threeClusters(f) : threeClusters(kDeforming, 1500, 0.25 * (f - kDeforming + 1));
        const std::vector<Object> objects = asObjects(meshes);
        Result got, levels;
        const Comparison c = runAndCompare(*culler, *reference, objects, got);
        visibility->run(objects, levels);
        const Stats& s = got.stats;
        EXPECT_EQ(s.gpuFallbacks, 0u) << "frame " << f << ": " << s.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << f << ": " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << "frame " << f;
        ASSERT_EQ(s.clusters, 3u) << "frame " << f;
        // The same levels in the same order as the reference runs them, a rerun's in its cluster's place.
        EXPECT_EQ(levelOutline(s), levelOutline(levels.stats)) << "frame " << f;
        reruns += s.levelReruns;
        if (f < kFrames - 2) continue;
        EXPECT_EQ(s.levelReruns, 0u) << "frame " << f;
        EXPECT_EQ(deferredLevels(s), 3u) << "frame " << f << ": each cluster's triangle level;" << levelCosts(s);
        EXPECT_EQ(s.blockingReadBacks, 1u) << "frame " << f << ": one wait for the three clusters;" << levelCosts(s);
    }
    EXPECT_GE(reruns, 1u) << "the first frames must run a deferred cluster again (its records built short)";
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GE(log->levelsDeferred, 3u * kFrames / 2) << log->summary();
}

std::vector<ObjectIndexPair> allPairs(std::size_t n) {
    std::vector<ObjectIndexPair> pairs;
    for (std::uint32_t a = 0; a < n; ++a)
        for (std::uint32_t b = a + 1; b < n; ++b) pairs.push_back({a, b});
    return pairs;
}

TEST(DeferredLevels, TheFramesWaitEndsAtItsBudget) {
    // A device whose read-back takes far longer than the frame's budget: the frame's one wait ends at the budget (a
    // fence polled until then), not when the device is done, and the frame is abandoned; the culler stays usable.
    Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    settings.gpuLevels = GpuLevels::Always;
    CULLIDE_GPU_CULLER_OR_SKIP(fast, settings);
    const std::vector<TriangleMesh> meshes = threeClusters(0, 300);
    const std::vector<Object> objects = asObjects(meshes);
    const std::vector<ObjectIndexPair> pairs = allPairs(objects.size());
    Result r;
    for (int f = 0; f < 3; ++f) fast->run(objects, pairs, r);
    const double frameMs = r.stats.totalMs;  // a steady frame on this machine, nothing slowed down
    const double budgetMs = 2.0 * frameMs + 20.0;
    GlBackendOptions slow;
    slow.readBackDelayMs = budgetMs + 300.0;
    std::unique_ptr<Culler> culler =
        createGpuCuller(settings, [&](const Settings& s) { return createGlPruningBackend(s, slow); });
    for (int f = 0; f < 3; ++f) culler->run(objects, pairs, r);  // the places learn their iterations
    ASSERT_EQ(r.stats.clusters, 3u);
    ASSERT_EQ(r.stats.levelReruns, 0u);
    ASSERT_EQ(r.stats.blockingReadBacks, 1u);
    const auto start = std::chrono::steady_clock::now();
    culler->run(objects, pairs, r, budgetMs);
    const double wallMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    EXPECT_TRUE(r.stats.abandoned);
    EXPECT_EQ(r.stats.blockingReadBacks, 1u) << "abandoned in the frame's wait";
    EXPECT_LT(wallMs, budgetMs + 200.0) << "the wait went on past the budget (" << budgetMs << " ms)";
    Result again, reference;
    culler->run(objects, pairs, again);
    createReferenceCuller(settings)->run(objects, pairs, reference);
    EXPECT_FALSE(again.stats.abandoned);
    EXPECT_EQ(trianglePairs(again), trianglePairs(reference));
}

}  // namespace
}  // namespace cullide::test
