// Static geometry (Object::staticKey): the culler keeps a static mesh's validation and triangle boxes between
// frames and recomputes them when (key, version, counts) change; results always equal the reference culler's.
#include "Compare.h"
#include "GlTestSupport.h"
#include "ReliableSettings.h"
#include "TriangleOrders.h"
#include "cullide/scenes/Procedural.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace cullide::test {
namespace {

void expectSameAsReference(const std::vector<Object>& objects, Culler& culler, Result& result, const char* what) {
    Result reference;
    createReferenceCuller(culler.settings())->run(objects, reference);
    culler.run(objects, result);
    const Comparison c = compare(reference, result);
    EXPECT_EQ(c.missed, 0u) << what << ": " << c.firstMissed;
    EXPECT_EQ(c.spurious, 0u) << what;
    EXPECT_TRUE(c.objectPairsEqual) << what;
    ASSERT_EQ(result.rejected.size(), reference.rejected.size()) << what;
    for (std::size_t i = 0; i < result.rejected.size(); ++i) {
        EXPECT_EQ(result.rejected[i].object, reference.rejected[i].object) << what;
        EXPECT_EQ(result.rejected[i].message, reference.rejected[i].message) << what;
    }
}

TEST(StaticCache, KeptWhileTheVersionStaysAndRecomputedWhenItChanges) {
    for (const GpuLevels levels : {GpuLevels::Auto, GpuLevels::Always}) {
        Settings settings;
        settings.gpuLevels = levels;
        settings.exactThreshold = 0;
        settings.resolution = 64;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
        auto meshes = randomSoups(5, 12, 200, 0.1);
        auto objects = asObjects(meshes);
        objects[0].staticKey = 42;
        objects[0].version = 1;
        Result result;
        expectSameAsReference(objects, *culler, result, "first frame");
        EXPECT_EQ(result.stats.staticObjectsReused, 0u);
        expectSameAsReference(objects, *culler, result, "second frame");
        EXPECT_EQ(result.stats.staticObjectsReused, 1u);
        // The static mesh moves onto another object: with a new version, the culler must see it there.
        const Vec3 shift = 0.5 * (meshes[1].vertices[0] - meshes[0].vertices[0]);
        for (Vec3& v : meshes[0].vertices) v += shift;
        objects[0].version = 2;
        expectSameAsReference(objects, *culler, result, "moved, new version");
        EXPECT_EQ(result.stats.staticObjectsReused, 0u);
        expectSameAsReference(objects, *culler, result, "moved, kept");
        EXPECT_EQ(result.stats.staticObjectsReused, 1u);
        // Fewer triangles under the same version: counts differ, so recomputed.
        meshes[0].triangles.resize(meshes[0].triangles.size() / 2);
        expectSameAsReference(objects, *culler, result, "fewer triangles, same version");
        EXPECT_EQ(result.stats.staticObjectsReused, 0u);
    }
}

TEST(StaticCache, StaticMeshesStayOnTheDeviceWhileTheOriginHolds) {
    // GPU levels forced (also on llvmpipe): a static mesh is sent once and kept resident at the front of the
    // buffers; the moving meshes are sent every frame. Pairs must equal the reference in every frame, also when a
    // far move rebuilds the region around a new origin and when the static mesh changes version.
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;
    settings.exactThreshold = 0;
    settings.resolution = 64;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    auto meshes = randomSoups(21, 6, 300, 0.5);  // large clusters: every mesh overlaps the others
    const auto original = meshes;
    auto objects = asObjects(meshes);
    objects[0].staticKey = 5;
    objects[0].version = 1;
    objects[2].staticKey = 6;  // a second static mesh: its place in the resident region is not the start
    const double staticBytes =
        4.0 * (3.0 * double(meshes[0].vertices.size()) + 3.0 * double(meshes[0].triangles.size()));
    Result result;
    std::vector<std::size_t> uploaded;
    for (int frame = 0; frame < 6; ++frame) {
        // Dynamic meshes wobble a little every frame; on frame 4 they all jump far away and back on frame 5.
        for (std::size_t m = 1; m < meshes.size(); ++m)
            for (std::size_t v = 0; v < meshes[m].vertices.size() && m != 2; ++v)
                meshes[m].vertices[v] = original[m].vertices[v] + Vec3(0.01 * frame, 0.0, frame == 4 ? 1e3 : 0.0);
        expectSameAsReference(objects, *culler, result, "resident static");
        ASSERT_EQ(result.stats.gpuFallbacks, 0u) << result.stats.gpuError;
        ASSERT_FALSE(result.stats.levels.empty()) << "GPU levels must run for this test to mean anything";
        // The device holds the four 64² view images (three views wide) and at least the uploaded geometry.
        EXPECT_GE(result.stats.gpuDeviceBytes, std::size_t{4} * 4 * 3 * 64 * 64 + std::size_t(staticBytes));
        if (frame != 4) {
            ASSERT_FALSE(result.pairs.empty());
            EXPECT_EQ(result.pairs.front().a, 0u) << "the static mesh must take part";
        }
        uploaded.push_back(result.stats.bytesUploaded);
    }
    // Frame 0 sends the static mesh, frames 1-3 do not (the rest — moving meshes, boxes — varies a little); frame 4
    // moves the origin away, frame 5 back: the static mesh is sent again, in one of them (as the clusters come).
    for (int frame = 1; frame <= 3; ++frame)
        EXPECT_LT(double(uploaded[frame]), double(uploaded[0]) - 0.9 * staticBytes) << frame;
    EXPECT_GT(double(uploaded[4] + uploaded[5]), 2.0 * double(uploaded[3]) + 0.9 * staticBytes);
    // A new version of the static mesh is sent again, and the culler sees it where it now is.
    for (Vec3& v : meshes[0].vertices) v += Vec3(0.05, 0.0, 0.0);
    objects[0].version = 2;
    expectSameAsReference(objects, *culler, result, "new static version");
    EXPECT_GT(double(result.stats.bytesUploaded), double(uploaded[3]) + 0.9 * staticBytes);
    expectSameAsReference(objects, *culler, result, "new static version, kept");
}

TEST(StaticCache, RejectedStaticMeshStaysRejectedInObjectOrder) {
    Settings settings;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    auto meshes = randomSoups(9, 6, 100, 0.1);
    meshes[1].vertices[meshes[1].triangles[3][0]].x() = std::nan("");
    meshes[4].triangles[2][1] = 100000;
    auto objects = asObjects(meshes);
    objects[4].staticKey = 7;  // cached rejection after a non-cached one
    Result result;
    for (int frame = 0; frame < 3; ++frame) {
        expectSameAsReference(objects, *culler, result, "frame");
        ASSERT_EQ(result.rejected.size(), 2u);
        EXPECT_EQ(result.rejected[0].object, 1u);
        EXPECT_EQ(result.rejected[1].object, 4u);
    }
    EXPECT_EQ(result.stats.staticObjectsReused, 1u);
}

// A mesh edited in place (same counts) that comes back under another key takes the spatial order kept for its mesh
// as an instance with another key does, until that order is recomputed: the device's resident region, which holds a
// static mesh's order with its triangles, then takes the mesh again.
TEST(StaticCache, TheResidentRegionFollowsTheMeshsSpatialOrder) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(64));
    TriangleMesh mesh = scenes::makeSphere(1.0, 48, 24);
    TriangleMesh partner = scenes::makeSphere(1.0, 32, 16);
    for (Vec3& v : partner.vertices) v += Vec3(1.3, 0.2, 0.1);
    const std::uint64_t frames = 2 * TriangleOrders::kRefreshFrames + 2;
    for (std::uint64_t frame = 0; frame < frames; ++frame) {
        if (frame == 1) {  // turned in place, and handed over under a new key
            const Eigen::Matrix3d turn = Eigen::AngleAxisd(1.3, Vec3(0.3, 0.5, 1).normalized()).toRotationMatrix();
            for (Vec3& v : mesh.vertices) v = turn * v;
        }
        std::vector<Object> objects(2);
        objects[0].mesh = &mesh;
        objects[0].staticKey = frame == 0 ? 1 : 2;
        objects[0].version = frame == 0 ? 1 : 2;
        objects[1].mesh = &partner;
        Result result;
        expectSameAsReference(objects, *culler, result, ("frame " + std::to_string(frame)).c_str());
        EXPECT_EQ(result.stats.gpuFallbacks, 0u) << result.stats.gpuError;
    }
}

TEST(StaticCache, KeyUsedTwiceInOneFrameIsNotConfused) {
    Settings settings;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    auto meshes = randomSoups(13, 8, 150, 0.1);
    meshes[3].triangles.resize(40);  // different counts under the same key
    auto objects = asObjects(meshes);
    objects[2].staticKey = objects[3].staticKey = 99;
    Result result;
    for (int frame = 0; frame < 3; ++frame) expectSameAsReference(objects, *culler, result, "shared key");
}

}  // namespace
}  // namespace cullide::test
