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

}  // namespace
}  // namespace cullide::test
