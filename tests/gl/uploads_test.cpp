// What the GL levels send of the geometry from frame to frame: only what changed since the last upload. The device's
// copy must then always be the frame's geometry: held to the CPU visibility reference (VisibilityLockstep) and to the
// exact reference culler while meshes deform, move, turn triangles over and reorder them with the same counts.
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

namespace cullide::test {
namespace {

TEST(Uploads, TheDeviceHoldsEachFramesGeometryWhenOnlyPartOfItIsSent) {
    const Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 128});
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    std::vector<TriangleMesh> meshes = randomSoups(7, 10, 80, 0.25);
    std::size_t firstFrameBytes = 0, restingFrameBytes = 0;
    for (int frame = 0; frame < 6; ++frame) {
        if (frame == 2)  // mesh 0 deforms (its positions change, not its indices): squashed and moved
            for (Vec3& v : meshes[0].vertices) v = Vec3(0.5 * v.x() + 0.2, v.y() + 0.15, v.z());
        if (frame == 3) std::reverse(meshes[1].triangles.begin(), meshes[1].triangles.end());  // same counts
        if (frame == 4)
            for (auto& t : meshes[2].triangles) std::swap(t[0], t[1]);  // every triangle turned over
        const std::vector<Object> objects = asObjects(meshes);
        Result r;
        const Comparison c = runAndCompare(*culler, *reference, objects, r);
        EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
        if (frame == 0) firstFrameBytes = r.stats.bytesUploaded;
        if (frame == 1) restingFrameBytes = r.stats.bytesUploaded;
    }
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GT(log->itemsPruned, 0u) << log->summary();
    // Nothing moved between frames 0 and 1: the second sends no positions or indices, only the levels' items and the
    // boxes (what is kept, exactly, is ClusterGeometry's unit test).
    EXPECT_LT(restingFrameBytes, firstFrameBytes);
}

// A frame at rest sends no geometry, no box and nothing per triangle but the triangle level's start bit: the group
// level's items, and per group where its triangles begin and where their range of the mesh's spatial order starts (the
// device generates the triangle items from them). The boxes (objects and groups) are the last frame's: at rest after
// the first frame, and again after a frame in which one mesh moved.
TEST(Uploads, AFrameAtRestSendsNothingPerTriangleButAStartBit) {
    Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::vector<TriangleMesh> meshes = randomSoups(17, 8, 600, 0.3);
    const std::vector<Object> objects = asObjects(meshes);
    std::size_t triangles = 0;
    for (const TriangleMesh& m : meshes) triangles += m.triangles.size();
    const auto expectAtRest = [&](const Stats& s, const char* frame) {
        ASSERT_EQ(s.levels.size(), 2u) << frame;
        ASSERT_EQ(s.levels[1].name, "triangles") << frame;
        const std::size_t groups = s.prepassGroupsOut;
        const std::size_t groupItems = 8 * groups;         // owner and primitive
        const std::size_t parents = 4 * (2 * groups + 1);  // where each group's triangles begin, its range's start
        const std::size_t startBits = 4 * ((triangles + 31) / 32);
        const std::size_t views = 2 * 160;                 // each level's first view
        const std::size_t expected = groupItems + parents + startBits + views;
        ASSERT_LT(expected, 4 * triangles) << "a scene where a word per triangle would show";
        EXPECT_LE(s.bytesUploaded, expected) << frame << ": " << groups << " groups, " << triangles << " triangles";
    };
    Result first, rest, moved, restAgain;
    culler->run(objects, first);
    culler->run(objects, rest);
    for (Vec3& v : meshes[3].vertices) v += Vec3(0.02, -0.01, 0.015);
    culler->run(objects, moved);
    culler->run(objects, restAgain);
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GT(first.stats.bytesUploaded, 12 * triangles) << "the first frame sends the geometry";
    EXPECT_GT(moved.stats.bytesUploaded, rest.stats.bytesUploaded) << "the moved mesh's positions and boxes";
    expectAtRest(rest.stats, "at rest");
    expectAtRest(restAgain.stats, "at rest after a move");
}

}  // namespace
}  // namespace cullide::test
