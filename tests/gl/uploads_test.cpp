// What the GL levels send of the geometry from frame to frame: only what changed since the last upload. The device's
// copy must then always be the frame's geometry: held to the CPU visibility reference (VisibilityLockstep) and to the
// exact reference culler while meshes deform, move, turn triangles over and reorder them with the same counts.
#include "Compare.h"
#include "GlTestSupport.h"
#include "cullide/scenes/Procedural.h"
#include "VisibilityLockstep.h"

#include <Eigen/Geometry>
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

/// What a level described by its objects sends: a range record per object (32 bytes) and a word per partner box.
std::size_t rangeBytes(std::size_t objects) { return 32 * objects + 4 * objects * (objects - 1); }

// A frame at rest sends no geometry, no box and nothing per group or triangle: the levels are described by their
// objects (a range each and its partners' boxes), and the device finds their items, their start (the box pre-pass)
// and their first views itself. The boxes (objects and groups) are the last frame's: at rest after the first frame,
// and again after a frame in which one mesh moved.
TEST(Uploads, AFrameAtRestSendsNothingPerGroupOrTriangle) {
    Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    settings.groupSize = 8;  // groups enough for a word per group to show
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::vector<TriangleMesh> meshes = randomSoups(17, 8, 600, 0.3);
    const std::vector<Object> objects = asObjects(meshes);
    const auto expectAtRest = [&](const Stats& s, const char* frame) {
        ASSERT_EQ(s.levels.size(), 2u) << frame;
        ASSERT_EQ(s.levels[1].name, "triangles") << frame;
        ASSERT_GT(4 * s.prepassGroupsIn, 2 * rangeBytes(meshes.size())) << frame << ": a word per group would show";
        EXPECT_LE(s.bytesUploaded, 2 * rangeBytes(meshes.size())) << frame;
    };
    Result first, rest, moved, restAgain;
    culler->run(objects, first);
    culler->run(objects, rest);
    for (Vec3& v : meshes[3].vertices) v += Vec3(0.02, -0.01, 0.015);
    culler->run(objects, moved);
    culler->run(objects, restAgain);
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GT(first.stats.bytesUploaded, 12 * meshes[0].triangles.size()) << "the first frame sends the geometry";
    EXPECT_GT(moved.stats.bytesUploaded, rest.stats.bytesUploaded) << "the moved mesh's positions and boxes";
    expectAtRest(rest.stats, "at rest");
    expectAtRest(restAgain.stats, "at rest after a move");
}

// A rigid body moving through a static mesh (env3's case; a mesh with a transform, as the Bullet adapter hands every
// body over) sends its transform, its object box and the levels' ranges: not its vertices, not its groups' boxes (the
// device builds them), nothing per group or triangle — under 1 KiB a frame. The levels stay held to the reference
// (lockstep) and the pairs to the exact reference's.
TEST(Uploads, ARigidBodyMovingThroughAStaticMeshSendsUnderAKibibyteAFrame) {
    Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    const TriangleMesh ground = scenes::makeSphere(1.0, 48, 24);
    const TriangleMesh body = scenes::makeTorus(0.3, 0.1, 32, 16);
    Transform pose;
    pose.translation = Vec3(0.0, 0.0, 0.95);
    std::vector<Object> objects(2);
    objects[0].mesh = &ground;
    objects[0].staticKey = 1;
    objects[0].version = 1;
    objects[1].mesh = &body;
    objects[1].transform = &pose;
    std::size_t pairs = 0;
    for (int frame = 0; frame < 4; ++frame) {
        Result got;
        const Comparison c = runAndCompare(*culler, *reference, objects, got);
        EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
        ASSERT_EQ(got.stats.levels.size(), 2u) << "frame " << frame;
        pairs += c.expected;
        if (frame == 0) {
            EXPECT_GT(got.stats.bytesUploaded, 12 * ground.vertices.size()) << "the first frame sends the meshes";
        } else {
            EXPECT_LT(got.stats.bytesUploaded, 1024u) << "frame " << frame;
        }
        pose.translation += Vec3(0.013, -0.007, 0.004);
        pose.linear = Eigen::AngleAxisd(0.05 * (frame + 1), Vec3(1, 2, 3).normalized()).toRotationMatrix();
    }
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GT(log->mappedVertices, 0u) << log->summary();
    EXPECT_GT(log->builtBoxes, 0u) << log->summary();
    EXPECT_GT(log->itemsPruned, 0u) << log->summary();
    EXPECT_GT(pairs, 0u) << "the body should touch the ground";
}

}  // namespace
}  // namespace cullide::test
