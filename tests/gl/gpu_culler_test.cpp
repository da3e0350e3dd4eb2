// The GPU culler against the brute-force reference: pruning, the margin, deforming and invalid objects, large
// offsets, sampled mode, the GPU-level policy, the raster backend, fewer axes, device errors.
#include "Compare.h"
#include "CullerBackends.h"
#include "GlTestSupport.h"
#include "ReliableSettings.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

namespace cullide::test {
namespace {

TEST(GpuCuller, TwoCrossingTriangles) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(64));
    std::vector<TriangleMesh> meshes(2);
    meshes[0].vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    meshes[0].triangles = {{0, 1, 2}};
    meshes[1].vertices = {{0.2, 0.2, -0.5}, {0.2, 0.2, 0.5}, {0.9, 0.9, 0.0}};
    meshes[1].triangles = {{0, 1, 2}};
    Result r;
    culler->run(asObjects(meshes), r);
    ASSERT_EQ(r.pairs.size(), 1u);
    EXPECT_EQ(r.pairs[0].triangles.size(), 1u);
    EXPECT_EQ(r.pcs, (std::vector<std::uint32_t>{0, 1}));
    EXPECT_FALSE(r.stats.renderer.empty());
}

Result runBoth(Culler& culler, const std::vector<Object>& objects, double margin, Comparison& cmp) {
    Settings s;
    s.margin = margin;
    auto reference = createReferenceCuller(s);
    Result expected, got;
    reference->run(objects, expected);
    culler.run(objects, got);
    cmp = compare(expected, got);
    return got;
}

TEST(GpuCuller, PrunesMostOfASparseScene) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(256));
    const auto meshes = randomSoups(11, 40, 100, 0.08);
    Comparison cmp;
    const Result r = runBoth(*culler, asObjects(meshes), 0.0, cmp);
    EXPECT_EQ(cmp.missed, 0u) << cmp.firstMissed;
    ASSERT_FALSE(r.stats.levels.empty());
    const LevelStats& last = r.stats.levels.back();
    ASSERT_GE(last.itemsPerIteration.size(), 2u);
    // The visibility levels must actually remove work: far fewer candidate pairs than all-pairs of the survivors.
    EXPECT_LT(last.itemsPerIteration.back(), last.itemsPerIteration.front());
    EXPECT_LT(r.stats.candidateTrianglePairs, 40u * 100u);
    EXPECT_GT(r.stats.bytesReadBack, 0u);
    EXPECT_GT(r.stats.draws, 0u);
}

TEST(GpuCuller, MarginReportsEveryPairWithinDistance) {
    for (double margin : {0.002, 0.02}) {
        Settings s = reliable(64);
        s.margin = margin;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, s);
        const auto meshes = randomSoups(5, 16, 60, 0.15);
        Comparison cmp;
        runBoth(*culler, asObjects(meshes), margin, cmp);
        EXPECT_EQ(cmp.missed, 0u) << "margin " << margin << ": " << cmp.firstMissed;
        EXPECT_EQ(cmp.spurious, 0u);
        EXPECT_GT(cmp.expected, 0u);
    }
}

// The device's box pre-pass keeps what the CPU's keeps at the edge of the margin (ClusterGeometry::prepassSlack):
// pairs of single triangles, far from the world origin, each facing the other at a distance short of the margin by
// 10^-10 to 4 * 10^-9 — less than the float rounding of their coordinates relative to the cluster's origin — so that
// a triangle's box meets its partner's box, inflated by margin / 2, only within that rounding.
TEST(GpuCuller, MarginPairsAtTheEdgeSurviveTheDevicesPrepass) {
    const double margin = 0.01;
    Settings s = reliable(64);
    s.margin = margin;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, s);
    std::vector<TriangleMesh> meshes;
    for (int k = 1; k <= 40; ++k) {
        const Vec3 at(1e6 + 3.0 * k, -2e6 + 0.37 * k, 0.013 * k);
        for (const double dz : {0.0, margin - 1e-10 * k}) {
            TriangleMesh m;
            m.vertices = {at + Vec3(0, 0, dz), at + Vec3(0.01, 0, dz), at + Vec3(0, 0.01, dz)};
            m.triangles = {{0, 1, 2}};
            meshes.push_back(m);
        }
    }
    Comparison cmp;
    const Result r = runBoth(*culler, asObjects(meshes), margin, cmp);
    EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
    EXPECT_GE(r.stats.clusters, 40u) << "a cluster per pair";
    EXPECT_EQ(cmp.expected, 40u) << "every pair lies within the margin";
    EXPECT_EQ(cmp.missed, 0u) << cmp.firstMissed;
}

TEST(GpuCuller, DeformingAppearingAndDisappearingObjects) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(128));
    auto meshes = randomSoups(21, 14, 50, 0.2);
    for (int frame = 0; frame < 8; ++frame) {
        // Deform every vertex, drop an object, add a new one, change triangle counts.
        for (std::size_t m = 0; m < meshes.size(); ++m)
            for (Vec3& v : meshes[m].vertices)
                v += 0.01 * Vec3(std::sin(frame + v.y() * 9), std::cos(frame + v.z() * 7), std::sin(v.x() * 5 - frame));
        if (frame % 2 == 1 && meshes.size() > 4) meshes.erase(meshes.begin() + frame % meshes.size());
        auto extra = randomSoups(100 + static_cast<std::uint64_t>(frame), 1, 20 + 10 * frame, 0.2);
        meshes.push_back(extra[0]);
        if (frame % 3 == 0) meshes[0].triangles.resize(meshes[0].triangles.size() / 2);
        Comparison cmp;
        runBoth(*culler, asObjects(meshes), 0.0, cmp);
        EXPECT_EQ(cmp.missed, 0u) << "frame " << frame << ": " << cmp.firstMissed;
        EXPECT_EQ(cmp.spurious, 0u);
        EXPECT_TRUE(cmp.objectPairsEqual) << "frame " << frame;
    }
}

TEST(GpuCuller, InvalidObjectsAndProxiesNeverHarmValidOnes) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(64));
    auto meshes = randomSoups(3, 10, 60, 0.2);
    TriangleMesh nan = meshes[0];
    nan.vertices[1].x() = std::nan("");
    TriangleMesh badIndex = meshes[1];
    badIndex.triangles[0][1] = 99999;
    meshes.push_back(nan);
    meshes.push_back(badIndex);
    meshes.push_back(TriangleMesh{});
    auto objects = asObjects(meshes);
    Object proxy;
    proxy.box.min = Vec3(0.4, 0.4, 0.4);
    proxy.box.max = Vec3(0.6, 0.6, 0.6);
    objects.push_back(proxy);
    Object infiniteProxy;
    infiniteProxy.box.min = Vec3(0, 0, 0);
    infiniteProxy.box.max = Vec3(1, 1, std::numeric_limits<double>::infinity());
    objects.push_back(infiniteProxy);
    Comparison cmp;
    const Result r = runBoth(*culler, objects, 0.0, cmp);
    EXPECT_EQ(cmp.missed, 0u) << cmp.firstMissed;
    EXPECT_EQ(cmp.spurious, 0u);
    EXPECT_TRUE(cmp.objectPairsEqual);
    ASSERT_EQ(r.rejected.size(), 3u);
    EXPECT_EQ(r.rejected[0].object, 10u);
    EXPECT_EQ(r.rejected[1].object, 11u);
    EXPECT_EQ(r.rejected[2].object, 14u);
    for (const ObjectPair& p : r.pairs) {
        EXPECT_NE(p.a, 10u);
        EXPECT_NE(p.b, 11u);
        if (p.b == 13u) {
            EXPECT_FALSE(p.hasTriangles);
        }
    }
}

TEST(GpuCuller, LargeOffsetsAndTinyObjects) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(32));
    for (double offset : {1e5, 1e7}) {
        auto meshes = randomSoups(8, 12, 40, 0.2);
        // Shrink half of the objects below a pixel and move everything far from the origin.
        for (std::size_t m = 0; m < meshes.size(); ++m)
            for (Vec3& v : meshes[m].vertices) {
                if (m % 2 == 0) v = Vec3(0.5, 0.5, 0.5) + (v - Vec3(0.5, 0.5, 0.5)) * 1e-3;
                v += Vec3(offset, -offset, offset);
            }
        Comparison cmp;
        runBoth(*culler, asObjects(meshes), 0.0, cmp);
        EXPECT_EQ(cmp.missed, 0u) << "offset " << offset << ": " << cmp.firstMissed;
        EXPECT_EQ(cmp.spurious, 0u);
    }
}

TEST(GpuCuller, SampledModeMissesAreCounted) {
    std::size_t missed = 0;
    std::size_t expected = 0;
    for (int resolution : {16, 64, 256}) {
        Settings s = reliable(resolution);
        s.mode = Mode::Sampled;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, s);
        for (std::uint64_t seed = 1; seed <= 3; ++seed) {
            Comparison cmp;
            runBoth(*culler, asObjects(randomSoups(seed, 16, 80, 0.2)), 0.0, cmp);
            EXPECT_EQ(cmp.spurious, 0u);  // the exact stage never reports a false pair
            missed += cmp.missed;
            expected += cmp.expected;
        }
        std::printf("sampled mode at %dx%d: missed %zu of %zu triangle pairs so far\n", resolution, resolution, missed,
                    expected);
    }
    EXPECT_GT(expected, 0u);
}

TEST(GpuCuller, AutoPolicyGivesTheSameResultWithOrWithoutGpuLevels) {
    Settings s;
    s.resolution = 64;
    CULLIDE_GPU_CULLER_OR_SKIP(publicAuto, s);
    // Auto's trial, on whatever device this is: the culler through the internal factory, which trials on a software
    // renderer too (createGpuCuller(settings) opens no context on one: checked below).
    const std::unique_ptr<Culler> autoCuller =
        createGpuCuller(s, [](const Settings& settings) { return createGlPruningBackend(settings); });
    CULLIDE_GPU_CULLER_OR_SKIP(gpuCuller, reliable(64));
    s.gpuLevels = GpuLevels::Never;
    CULLIDE_GPU_CULLER_OR_SKIP(cpuCuller, s);
    const auto meshes = randomSoups(77, 20, 80, 0.2);
    const auto objects = asObjects(meshes);
    Result a, g, c;
    autoCuller->run(objects, a);
    gpuCuller->run(objects, g);
    cpuCuller->run(objects, c);
    EXPECT_TRUE(compare(g, a).objectPairsEqual);
    EXPECT_TRUE(compare(g, c).objectPairsEqual);
    EXPECT_EQ(trianglePairs(g), trianglePairs(a));
    EXPECT_EQ(trianglePairs(g), trianglePairs(c));
    EXPECT_FALSE(g.stats.levels.empty());
    EXPECT_TRUE(c.stats.levels.empty());
    EXPECT_EQ(g.stats.autoDecision, "");
    EXPECT_EQ(c.stats.autoDecision, "");
    // Auto measures: frames 1-4 alternate the CPU path and the GPU levels, then the faster of the timed ones runs.
    EXPECT_TRUE(a.stats.levels.empty());
    EXPECT_EQ(a.stats.autoDecision, "measuring");
    for (int frame = 2; frame <= 5; ++frame) {
        autoCuller->run(objects, a);
        EXPECT_EQ(trianglePairs(g), trianglePairs(a)) << frame;
        // A GPU trial frame runs the levels, unless they ran past the frame's budget (the last CPU frame plus 1 ms:
        // llvmpipe's levels may) and it was finished on the CPU path.
        if (frame <= 4 && frame % 2 == 1) {
            EXPECT_TRUE(a.stats.levels.empty()) << frame;
        }
        if (frame <= 4 && frame % 2 == 0) {
            EXPECT_TRUE(!a.stats.levels.empty() || a.stats.autoTrialsAbandoned == 1) << frame;
        }
    }
    const bool gpu = a.stats.autoGpuMs < a.stats.autoCpuMs;
    EXPECT_GT(a.stats.autoCpuMs, 0.0);
    EXPECT_GT(a.stats.autoGpuMs, 0.0);
    EXPECT_EQ(a.stats.autoDecision, gpu ? "gpu" : "cpu") << a.stats.autoCpuMs << " " << a.stats.autoGpuMs;
    EXPECT_EQ(a.stats.levels.empty(), !gpu) << a.stats.renderer;

    // The public factory: GPU levels under Auto on a hardware device only; on a software renderer no context.
    Result p;
    publicAuto->run(objects, p);
    EXPECT_EQ(trianglePairs(g), trianglePairs(p));
    if (!hasHardwareGlDevice()) {
        EXPECT_EQ(p.stats.device, "none");
        EXPECT_TRUE(p.stats.levels.empty());
        EXPECT_NE(p.stats.gpuUnavailable.find("hardware devices only"), std::string::npos) << p.stats.gpuUnavailable;
    }
}

TEST(GpuCuller, AGpuTrialFramePastItsBudgetIsFinishedOnTheCpuPath) {
    // A device whose every read-back takes 40 ms: the GPU trial frames run past their budget (the last CPU frame
    // plus 1 ms) and are finished on the CPU path, the frames stay what the CPU path gives, and the CPU path wins.
    Settings s = reliable(64);
    s.gpuLevels = GpuLevels::Auto;
    s.exactThreshold = 0;  // levels for every cluster
    CULLIDE_GPU_CULLER_OR_SKIP(probe, s);
    GlBackendOptions slow;
    slow.readBackDelayMs = 40.0;
    const auto culler = createGpuCuller(s, [&](const Settings& settings) { return createGlPruningBackend(settings, slow); });
    // Three clusters far apart: the budget is looked at as each cluster's levels start and bounds the frame's one
    // wait for the device, so a trial frame is abandoned by its budget wherever it is (DeferredLevels tests the wait).
    std::vector<TriangleMesh> meshes;
    for (int c = 0; c < 3; ++c)
        for (TriangleMesh& m : randomSoups(91 + static_cast<std::uint64_t>(c), 8, 120, 0.25)) {
            for (Vec3& p : m.vertices) p.x() += 10.0 * c;
            meshes.push_back(std::move(m));
        }
    const auto objects = asObjects(meshes);
    Result reference, r;
    createReferenceCuller(s)->run(objects, reference);
    Settings always = s;
    always.gpuLevels = GpuLevels::Always;
    CULLIDE_GPU_CULLER_OR_SKIP(levels, always);
    Result clusters;
    levels->run(objects, clusters);
    ASSERT_EQ(clusters.stats.clusters, 3u);
    std::size_t abandoned = 0;
    double worstGpuTrialMs = 0.0, cpuFrameMs = 0.0;
    std::size_t worstTrialReadBacks = 0;
    for (int frame = 0; frame < 4; ++frame) {
        culler->run(objects, r);
        EXPECT_EQ(trianglePairs(r), trianglePairs(reference)) << frame;
        abandoned += r.stats.autoTrialsAbandoned;
        if (frame % 2 == 1 && r.stats.totalMs > worstGpuTrialMs) {
            worstGpuTrialMs = r.stats.totalMs;
            worstTrialReadBacks = r.stats.blockingReadBacks;
        }
        else cpuFrameMs = std::max(cpuFrameMs, r.stats.totalMs);
    }
    EXPECT_EQ(abandoned, 2u) << "both GPU trial frames";
    EXPECT_EQ(r.stats.autoDecision, "cpu");
    // Abandoned at the latest in the frame's wait, which ends at the budget (a rerun's read-backs may come first).
    EXPECT_LE(worstTrialReadBacks, 3u) << "one cluster's read-backs";
    EXPECT_LT(worstGpuTrialMs, cpuFrameMs + 1.0 + 40.0 * static_cast<double>(worstTrialReadBacks) + 40.0) << cpuFrameMs;
}

TEST(GpuCuller, RasterBackendAgreesWithCompute) {
    Settings s = reliable(64);
    s.backend = Backend::Raster;
    CULLIDE_GPU_CULLER_OR_SKIP(raster, s);
    CULLIDE_GPU_CULLER_OR_SKIP(compute, reliable(64));
    const auto meshes = randomSoups(9, 12, 60, 0.2);
    Result r, c;
    raster->run(asObjects(meshes), r);
    compute->run(asObjects(meshes), c);
    EXPECT_EQ(trianglePairs(r), trianglePairs(c));
    ASSERT_EQ(r.stats.levels.size(), c.stats.levels.size());
    // Same shader code for the test itself: the same survivors at every level and iteration.
    for (std::size_t l = 0; l < r.stats.levels.size(); ++l)
        EXPECT_EQ(r.stats.levels[l].itemsPerIteration, c.stats.levels[l].itemsPerIteration) << l;
}

TEST(GpuCuller, FewerAxesStayReliableAndPruneLess) {
    const auto meshes = randomSoups(31, 16, 80, 0.2);
    const auto objects = asObjects(meshes);
    Result all, xOnly, reference;
    createReferenceCuller(Settings{})->run(objects, reference);
    CULLIDE_GPU_CULLER_OR_SKIP(full, reliable(64));
    Settings s = reliable(64);
    s.axes = 1;
    CULLIDE_GPU_CULLER_OR_SKIP(single, s);
    full->run(objects, all);
    single->run(objects, xOnly);
    EXPECT_EQ(compare(reference, xOnly).missed, 0u);
    EXPECT_TRUE(compare(reference, xOnly).objectPairsEqual);
    ASSERT_FALSE(xOnly.stats.levels.empty());
    // One axis can only keep more (or the same) candidates than three.
    EXPECT_GE(xOnly.stats.candidateTrianglePairs, all.stats.candidateTrianglePairs);
    s.axes = 0;
    EXPECT_NE(s.validate(), "");
}

TEST(GpuCuller, UnknownDeviceIsAClearError) {
    Settings s;
    s.device = "99";
    s.gpuLevels = GpuLevels::Always;  // demanded GPU levels: no CPU-path fallback (tests/unit/no_gl_test.cpp)
    try {
        createGpuCuller(s);
        FAIL() << "expected GlUnavailableError";
    } catch (const GlUnavailableError& e) {
        EXPECT_NE(std::string(e.what()).find("99"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("libegl"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace cullide::test
