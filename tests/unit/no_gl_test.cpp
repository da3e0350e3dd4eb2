// The CPU path needs no GL (issue 13, items 5 and 6): with GpuLevels::Never the GPU culler opens no GL context,
// with GpuLevels::Auto it runs the CPU path (with a notice) when there is no usable GL device, and only where GPU
// levels are demanded (GpuLevels::Always, Pipeline::Paper) does a missing device throw GlUnavailableError. The
// device is made unusable with a device preference that cannot exist ("99"), which the EGL code refuses.
#include "CullerBackends.h"
#include "Compare.h"
#include "cullide/TaskPool.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

namespace cullide::test {
namespace {

constexpr const char* kNoSuchDevice = "99";

Settings withoutDevice(GpuLevels levels, Pipeline pipeline = Pipeline::Auto) {
    Settings s;
    s.gpuLevels = levels;
    s.pipeline = pipeline;
    s.resolution = 64;
    s.device = kNoSuchDevice;
    return s;
}

/// Runs `culler` on a small soup scene and expects exactly the reference's pairs.
Result expectSameAsReference(Culler& culler, std::uint64_t seed) {
    const auto meshes = randomSoups(seed, 12, 60, 0.2);
    const auto objects = asObjects(meshes);
    Result reference, result;
    createReferenceCuller(culler.settings())->run(objects, reference);
    culler.run(objects, result);
    const Comparison c = compare(reference, result);
    EXPECT_GT(c.expected, 0u) << "scene too sparse to test anything";
    EXPECT_EQ(c.missed, 0u) << c.firstMissed;
    EXPECT_EQ(c.spurious, 0u);
    EXPECT_TRUE(c.objectPairsEqual);
    return result;
}

void expectNoGlInStats(const Stats& stats) {
    EXPECT_EQ(stats.device, "none");
    EXPECT_EQ(stats.renderer, "");
    EXPECT_FALSE(stats.gpuUnavailable.empty());
    EXPECT_TRUE(stats.levels.empty());
    EXPECT_EQ(stats.draws, 0u);
    EXPECT_EQ(stats.bytesUploaded, 0u);
    EXPECT_EQ(stats.gpuDeviceBytes, 0u);
    EXPECT_EQ(stats.gpuFallbacks, 0u);
}

TEST(NoGl, NeverOpensNoContextAndMatchesTheReference) {
    testing::internal::CaptureStderr();
    std::unique_ptr<Culler> culler;
    ASSERT_NO_THROW(culler = createGpuCuller(withoutDevice(GpuLevels::Never)));
    for (std::uint64_t seed : {1u, 2u}) {
        const Result r = expectSameAsReference(*culler, seed);
        expectNoGlInStats(r.stats);
        EXPECT_NE(r.stats.gpuUnavailable.find("Never"), std::string::npos) << r.stats.gpuUnavailable;
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << "GpuLevels::Never is no reason for a notice";
}

TEST(NoGl, RefillsTheSurvivorListsOfTheResultItIsGiven) {
    // A Result reused frame after frame lends its survivor lists back to the culler: a frame with fewer survivors
    // keeps the capacity of a larger one, so the next larger frame writes into memory already mapped (a fresh exact-fit
    // list per frame cost a page fault per 4 KiB on large meshes).
    const auto culler = createGpuCuller(withoutDevice(GpuLevels::Never));
    std::vector<TriangleMesh> meshes = randomSoups(7, 1, 400, 0.5);
    meshes.push_back(meshes[0]);
    double lo = meshes[0].vertices[0].x(), hi = lo;
    for (const Vec3& v : meshes[0].vertices) {
        lo = std::min(lo, v.x());
        hi = std::max(hi, v.x());
    }
    const double width = hi - lo;
    for (Vec3& v : meshes[1].vertices) v.x() += 0.05 * width;  // nearly on top of each other: most triangles survive
    Result result;
    culler->run(asObjects(meshes), result);
    ASSERT_EQ(result.pcsTriangles.size(), 2u);
    const std::size_t before = result.pcsTriangles[0].size();
    for (Vec3& v : meshes[1].vertices) v.x() += 0.8 * width;  // a sliver of overlap: few survivors
    culler->run(asObjects(meshes), result);
    const std::vector<std::uint32_t>& after = result.pcsTriangles[0];
    ASSERT_GT(after.size(), 0u) << "the objects must still overlap";
    ASSERT_LT(2 * after.size(), before) << "the second frame must have far fewer survivors";
    EXPECT_GE(after.capacity(), before);
    Result reference;  // and the lists are right: the same as a fresh Result's
    createGpuCuller(withoutDevice(GpuLevels::Never))->run(asObjects(meshes), reference);
    EXPECT_EQ(result.pcsTriangles, reference.pcsTriangles);
}

TEST(NoGl, ALargePairsTrianglesAreExactAndSortedOnAnyThreadCount) {
    // Two dense soups on top of each other: their one pair is split into many descent tasks, whose hits are sorted
    // per task and merged. The list must be the reference's, sorted and without repeats, whatever the workers.
    std::vector<TriangleMesh> meshes = randomSoups(11, 1, 3000, 0.5);
    meshes.push_back(meshes[0]);
    for (Vec3& v : meshes[1].vertices) v.x() += 0.01;
    const auto objects = asObjects(meshes);
    Result reference;
    createReferenceCuller(withoutDevice(GpuLevels::Never))->run(objects, reference);
    for (const unsigned threads : {1u, 3u, 5u}) {
        Settings settings = withoutDevice(GpuLevels::Never);
        settings.threads = threads;
        Result result;
        createGpuCuller(settings)->run(objects, result);
        const Comparison c = compare(reference, result);
        ASSERT_GT(c.expected, 500u) << "the scene must give one large pair";
        EXPECT_EQ(c.missed, 0u) << threads << " threads: " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << threads << " threads";
        for (const ObjectPair& pair : result.pairs) {
            EXPECT_TRUE(std::is_sorted(pair.triangles.begin(), pair.triangles.end())) << threads << " threads";
            EXPECT_EQ(std::adjacent_find(pair.triangles.begin(), pair.triangles.end()), pair.triangles.end());
        }
        EXPECT_GT(result.stats.candidateTrianglePairs, 4 * c.expected / 3) << "no work left for the split";
    }
}

TEST(NoGl, AFrameWakesItsWorkersAheadOfItsLoops) {
    // Between frames the workers sleep (the application runs). A frame wakes them when it starts, so its parallel
    // loops find them polling: Stats counts the wake-ups a loop had to wait for, and a frame should have none.
    std::vector<TriangleMesh> meshes = randomSoups(11, 1, 3000, 0.5);
    meshes.push_back(meshes[0]);
    for (Vec3& v : meshes[1].vertices) v.x() += 0.01;
    const auto objects = asObjects(meshes);
    Settings settings = withoutDevice(GpuLevels::Never);
    settings.threads = 2;
    const auto culler = createGpuCuller(settings);
    Result result;
    culler->run(objects, result);
    // A loaded machine may keep a thread off its CPU for a while: half the frames, in one of a few rounds.
    std::size_t calls = 0, wakes = 0, framesWithout = 0;
    for (int round = 0; round < 3 && framesWithout < 4; ++round) {
        calls = wakes = framesWithout = 0;
        for (int frame = 0; frame < 8; ++frame) {
            std::this_thread::sleep_for(TaskPool::kSpin * 20);  // the workers fall asleep
            culler->run(objects, result);
            calls += result.stats.poolCalls;
            wakes += result.stats.poolWorkerWakes;
            framesWithout += result.stats.poolWorkerWakes == 0 ? 1 : 0;
        }
    }
    EXPECT_GE(calls, 8u) << "the frame must hand loops to its workers";
    EXPECT_GE(framesWithout, 4u) << wakes << " wake-ups in 8 frames";  // without the early wake-up: 0 or 1
}

/// One frame of `objects` through both cullers: the culler's pairs must be the reference's, and every triangle of
/// a pair in its PCS. Returns the reference's triangle pairs.
std::size_t expectSameFrame(Culler& reference, Culler& culler, const std::vector<Object>& objects, Result& got,
                            int frame) {
    Result want;
    reference.run(objects, want);
    culler.run(objects, got);
    const Comparison c = compare(want, got);
    EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
    EXPECT_EQ(c.spurious, 0u) << "frame " << frame;
    return c.expected;
}

TEST(NoGl, KeptSpatialOrdersOnlyChangeSpeed) {
    // A rigid sphere (a transform) turning inside a static torus (staticKey), and a soup whose triangles are shuffled
    // in place every frame (the same mesh and counts: its kept order is stale every frame). The exact stage's trees
    // follow the kept orders (refits, or whole-mesh trees built in the order); every frame's pairs must still be the
    // reference's.
    const TriangleMesh sphere = scenes::makeSphere(0.5, 40, 20);
    const TriangleMesh torus = scenes::makeTorus(1.0, 0.4, 60, 30);
    TriangleMesh soup = randomSoups(17, 1, 600, 0.8)[0];
    for (Vec3& v : soup.vertices) v += Vec3(1.0, 0.0, 0.0);
    std::mt19937 rng(5);
    std::unique_ptr<Culler> culler = createGpuCuller(withoutDevice(GpuLevels::Never));
    std::unique_ptr<Culler> reference = createReferenceCuller(withoutDevice(GpuLevels::Never));
    constexpr int kFrames = 40;
    std::size_t refits = 0, orders = 0, expected = 0, kept = 0;
    for (int f = 0; f < kFrames; ++f) {
        Transform t;
        t.linear = Eigen::AngleAxisd(0.07 * f, Vec3(0.3, 0.2, 1.0).normalized()).toRotationMatrix();
        t.translation = Vec3(1.0 + 0.005 * f, 0.0, 0.0);
        std::shuffle(soup.triangles.begin(), soup.triangles.end(), rng);
        std::vector<Object> objects(3);
        objects[0].mesh = &sphere;
        objects[0].transform = &t;
        objects[1].mesh = &torus;
        objects[1].staticKey = 1;
        objects[1].version = 1;
        objects[2].mesh = &soup;
        Result got;
        expected += expectSameFrame(*reference, *culler, objects, got, f);
        refits += got.stats.exactTreesRefit + got.stats.exactTreesWhole;
        orders += got.stats.meshOrdersComputed;
        kept += got.stats.exactTreesKept;
    }
    EXPECT_GT(expected, 100u * kFrames) << "the scene must give pairs every frame";
    EXPECT_GE(refits, 2u * kFrames + 1) << "the sphere's and the soup's trees follow their kept orders";
    EXPECT_EQ(kept, kFrames - 1u) << "the static torus's tree is built once";
    // Three meshes, each recomputed at most every TriangleOrders::kRefreshFrames frames after a staggered first one
    // (the static torus only once).
    EXPECT_LE(orders, 3u * (1 + kFrames / 16));
    EXPECT_GE(orders, 2u);
}

TEST(NoGl, WholeMeshTreesMatchTheReference) {
    // The CPU path's trees of whole meshes (MeshTrees), with a margin (their leaves are inflated like every box):
    // - a static landscape (staticKey) under 24 spheres, its tree built once and kept, and built again when its
    //   version changes (it is raised mid-run: a stale tree would miss and invent pairs);
    // - a deforming torus around a sphere (its box mostly near its partner's): a tree from its vertices each frame;
    // - an object whose box barely meets its partner's: no whole tree, the pre-pass and a tree of its survivors.
    // Every frame's pairs must be the reference's, and every triangle of a pair in the PCS (compare()).
    TriangleMesh landscape = scenes::makeTorus(4.0, 0.3, 120, 24);  // a ring of rock, flattened below
    for (Vec3& v : landscape.vertices) v.z() *= 0.3;  // the ring lies in the xy plane: z is up
    const TriangleMesh ball = scenes::makeSphere(0.2, 16, 8);
    const TriangleMesh torusRest = scenes::makeTorus(0.6, 0.15, 48, 16);
    TriangleMesh torus = torusRest;
    const TriangleMesh far = scenes::makeSphere(0.3, 16, 8);
    constexpr int kBalls = 24;
    std::vector<Transform> poses(kBalls + 3);
    Settings settings = withoutDevice(GpuLevels::Never);
    settings.margin = 0.01;
    std::unique_ptr<Culler> culler = createGpuCuller(settings);
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    constexpr int kFrames = 24;
    std::uint64_t version = 1;
    std::size_t expected = 0, whole = 0, kept = 0, builtAgain = 0;
    for (int f = 0; f < kFrames; ++f) {
        if (f == kFrames / 2) {  // the landscape rises by a ball's radius: its kept tree is stale now
            for (Vec3& v : landscape.vertices) v.z() += 0.2;
            ++version;
        }
        std::vector<Object> objects(kBalls + 4);
        objects[0].mesh = &landscape;
        objects[0].staticKey = 7;
        objects[0].version = version;
        for (int i = 0; i < kBalls; ++i) {
            const double angle = 6.2831853 * i / kBalls + 0.01 * f;
            poses[i].translation = Vec3(4.0 * std::cos(angle), 4.0 * std::sin(angle), 0.12 + 0.004 * f);
            objects[1 + i].mesh = &ball;
            objects[1 + i].transform = &poses[i];
        }
        for (std::size_t k = 0; k < torus.vertices.size(); ++k) {
            const Vec3& p = torusRest.vertices[k];
            torus.vertices[k] = Vec3(p.x() * (1.0 + 0.05 * std::sin(0.3 * f + p.z())), p.y(), p.z()) +
                                Vec3(20.0, 0.0, 0.0);
        }
        objects[kBalls + 1].mesh = &torus;
        poses[kBalls].translation = Vec3(20.0 + 0.55 + 0.003 * f, 0.0, 0.0);
        objects[kBalls + 2].mesh = &ball;
        objects[kBalls + 2].transform = &poses[kBalls];
        poses[kBalls + 1].translation = Vec3(-20.0, 0.0, 0.0);
        poses[kBalls + 2].translation = Vec3(-20.0 + 0.59 - 0.002 * f, 0.0, 0.0);
        objects[kBalls + 3].mesh = &far;
        objects[kBalls + 3].transform = &poses[kBalls + 1];
        objects.push_back(Object{});
        objects.back().mesh = &far;
        objects.back().transform = &poses[kBalls + 2];
        Result got;
        expected += expectSameFrame(*reference, *culler, objects, got, f);
        whole += got.stats.exactTreesWhole;
        kept += got.stats.exactTreesKept;
        if (f == kFrames / 2) builtAgain = got.stats.exactTreesWhole;
        EXPECT_GE(got.stats.exactTreesRefit + got.stats.exactTreesSorted, 1u) << "frame " << f << ": the far pair";
    }
    EXPECT_GT(expected, 50u * kFrames) << "the scene must give pairs every frame";
    EXPECT_EQ(kept, kFrames - 2u) << "the landscape's tree, kept but for its two versions' first frames";
    EXPECT_GE(builtAgain, 1u) << "the landscape's new version gets a new tree";
    EXPECT_GE(whole, kFrames + 2u) << "the torus every frame, the landscape twice";
}

/// The notice lines ("cullide: ...") in captured standard error; lines of the EGL/Mesa libraries are not counted.
std::size_t noticeLines(const std::string& text) {
    std::size_t lines = 0;
    for (std::size_t at = text.find("cullide:"); at != std::string::npos; at = text.find("cullide:", at + 1)) ++lines;
    return lines;
}

TEST(NoGl, AutoOpensNoContextWithoutAHardwareDevice) {
    // GpuLevels::Auto runs GPU levels on hardware devices only: for a device that is none (here: an index no device
    // has), no GL context is opened and nothing is printed; the stats say why.
    Settings settings = withoutDevice(GpuLevels::Auto);
    settings.device = "917";
    ASSERT_FALSE(hasHardwareGlDevice(settings.device));
    testing::internal::CaptureStderr();
    std::unique_ptr<Culler> culler;
    ASSERT_NO_THROW(culler = createGpuCuller(settings));
    const Result first = expectSameAsReference(*culler, 3);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
    expectNoGlInStats(first.stats);
    EXPECT_NE(first.stats.gpuUnavailable.find("hardware devices only"), std::string::npos)
        << first.stats.gpuUnavailable;
    EXPECT_EQ(first.stats.autoDecision, "");
    EXPECT_FALSE(hasHardwareGlDevice("software"));
    EXPECT_FALSE(hasHardwareGlDevice("surfaceless"));
}

TEST(NoGl, AutoRunsTheCpuPathWithOneNotice) {
    // A backend that cannot be made (a device that fails to give a context), with a reason no run of this test used
    // before in this process (--gtest_repeat): the notice names it, and a notice is given once per process and reason.
    static int run = 0;
    const std::string reason = "no context on device " + std::to_string(900 + run++);
    const PruningBackendFactory failing = [&](const Settings&) -> std::unique_ptr<PruningBackend> {
        throw GlUnavailableError(reason);
    };
    const Settings settings = withoutDevice(GpuLevels::Auto);
    testing::internal::CaptureStderr();
    std::unique_ptr<Culler> culler;
    ASSERT_NO_THROW(culler = createGpuCuller(settings, failing));
    const Result first = expectSameAsReference(*culler, 3);
    const Result second = expectSameAsReference(*culler, 4);
    const std::string notice = testing::internal::GetCapturedStderr();
    expectNoGlInStats(first.stats);
    expectNoGlInStats(second.stats);
    // One line (not one per frame), naming what is missing: the GlUnavailableError's message.
    EXPECT_EQ(noticeLines(notice), 1u) << notice;
    EXPECT_NE(notice.find("CPU path"), std::string::npos) << notice;
    EXPECT_NE(notice.find(reason), std::string::npos) << notice;
    EXPECT_EQ(first.stats.gpuUnavailable, reason);
    EXPECT_EQ(second.stats.gpuUnavailable, first.stats.gpuUnavailable);

    // A second culler for the same reason (the Bullet adapter re-creates its culler as its margin grows) says why
    // in its stats, but does not repeat the notice.
    testing::internal::CaptureStderr();
    ASSERT_NO_THROW(culler = createGpuCuller(settings, failing));
    const Result again = expectSameAsReference(*culler, 5);
    EXPECT_EQ(noticeLines(testing::internal::GetCapturedStderr()), 0u);
    EXPECT_EQ(again.stats.gpuUnavailable, first.stats.gpuUnavailable);
}

TEST(NoGl, DemandedGpuLevelsStillThrow) {
    EXPECT_THROW(createGpuCuller(withoutDevice(GpuLevels::Always)), GlUnavailableError);
    EXPECT_THROW(createGpuCuller(withoutDevice(GpuLevels::Auto, Pipeline::Paper)), GlUnavailableError);
    EXPECT_THROW(createGpuCuller(withoutDevice(GpuLevels::Always, Pipeline::Paper)), GlUnavailableError);
}

}  // namespace
}  // namespace cullide::test
