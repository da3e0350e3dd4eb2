// The cluster upload (ClusterGeometry.h) built on the mesh cache, without GL: static meshes sent once, the others
// with every upload.
#include "ClusterGeometry.h"
#include "MeshCacheSupport.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <cmath>

#include <string>
#include <vector>

namespace cullide::test {
namespace {

using scenes::makeBox;
using scenes::transformMesh;

/// Keeps what the culler hands to the device.
class RecordingBackend final : public PruningBackend {
public:
    std::vector<GpuGeometry> uploads;
    void upload(const GpuGeometry& geometry, Stats&) override { uploads.push_back(geometry); }
    void forgetUploads() override {}
    std::size_t deviceBytes() const override { return 0; }
    std::string renderer() const override { return "recording"; }
    std::string device() const override { return "none"; }
    void pruneLevel(const LevelItems&, const LevelStart&, std::vector<std::uint8_t>&, LevelStats&, Stats&,
                    std::vector<IterationTrace>*) override {}  // prunes nothing
    void pruneLevelAhead(const LevelItems&, const LevelStart&, std::size_t, Stats&,
                         std::vector<IterationTrace>*) override {}
    void settle(Stats&) override {}
};

TEST(ClusterGeometry, StaticMeshesAreSentOnceAndOthersEveryUpload) {
    const TriangleMesh ground = makeBox(Vec3(4, 4, 0.5));
    TriangleMesh body = makeBox(Vec3::Constant(0.5));
    transformMesh(body, Eigen::Affine3d(Eigen::Translation3d(0, 0, 0.9)));
    const std::vector<Object> objects = {staticObject(ground, 1), Object{}, staticObject(body, 0)};
    FrameState frame;
    frame.objects = &objects;
    frame.valid = {ValidatedObject{true, true, {Vec3(-4, -4, -0.5), Vec3(4, 4, 0.5)}},
                   ValidatedObject{true, false, {Vec3(3, 3, 0), Vec3(5, 5, 1)}},
                   ValidatedObject{true, true, {Vec3(-0.5, -0.5, 0.4), Vec3(0.5, 0.5, 1.4)}}};
    Cluster cluster;
    cluster.objects = {0, 1, 2};
    cluster.groups = {Group{2, 0, 12, frame.valid[2].box}};
    StaticMeshCache cache;
    ClusterGeometry geometry;
    RecordingBackend backend;
    TaskPool pool(1);
    Stats stats;
    for (int f = 0; f < 2; ++f) {
        frame.statics = lookUpAndCheck(cache, objects);
        geometry.upload(frame, cluster, backend, pool, stats);
    }
    ASSERT_EQ(backend.uploads.size(), 2u);
    const GpuGeometry& first = backend.uploads[0];
    const GpuGeometry& second = backend.uploads[1];
    EXPECT_EQ(first.keptPositions, 0u);
    // Nothing changed: the ground (static) and the body (not static, the same) stay on the device.
    EXPECT_EQ(second.keptPositions, second.positions.size());
    EXPECT_EQ(second.keptIndices, second.indices.size());
    EXPECT_EQ(first.positions, second.positions);
    EXPECT_EQ(first.indices, second.indices);
    EXPECT_EQ(geometry.baseTriangle(0), 0u);
    EXPECT_EQ(geometry.baseTriangle(2), ground.triangles.size());
    // The body's indices are global: they point past the ground's vertices.
    EXPECT_EQ(second.indices[3 * ground.triangles.size()], ground.vertices.size() + body.triangles[0][0]);
    // Three object boxes and one group box, relative to the cluster's centre (0.5, 0.5, 0.45), rounded outwards.
    ASSERT_EQ(second.boxes.size(), 4u * 6u);
    EXPECT_EQ(geometry.objectBox(1), 1u);
    EXPECT_EQ(geometry.groupBox(0), 3u);
    EXPECT_FLOAT_EQ(second.boxes[6 + 0], 2.5f);
    EXPECT_FLOAT_EQ(second.boxes[6 + 5], 0.55f);
    EXPECT_DOUBLE_EQ(second.coordinateBound, 4.5);
}

/// A mesh that is not static is sent from where it first differs from the last upload: its positions when it moves
/// or deforms (not its indices), its indices from the first triangle that changed. Bit for bit: -0 is not +0.
TEST(ClusterGeometry, OnlyWhatChangedSinceTheLastUploadIsSent) {
    const TriangleMesh ground = makeBox(Vec3(4, 4, 0.5));
    TriangleMesh body = makeBox(Vec3::Constant(0.5));
    const std::vector<Object> objects = {staticObject(ground, 1), staticObject(body, 0)};
    FrameState frame;
    frame.objects = &objects;
    frame.valid = {ValidatedObject{true, true, {Vec3(-4, -4, -0.5), Vec3(4, 4, 0.5)}},
                   ValidatedObject{true, true, {Vec3(-0.5, -0.5, -0.5), Vec3(0.5, 0.5, 0.5)}}};
    Cluster cluster;
    cluster.objects = {0, 1};
    StaticMeshCache cache;
    ClusterGeometry geometry;
    RecordingBackend backend;
    TaskPool pool(2);
    Stats stats;
    const auto upload = [&] {
        frame.statics = lookUpAndCheck(cache, objects);
        geometry.upload(frame, cluster, backend, pool, stats);
        return backend.uploads.back();
    };
    upload();
    const std::size_t groundFloats = 3 * ground.vertices.size(), groundIndices = 3 * ground.triangles.size();
    body.vertices[2].y() += 0.25;  // deforms: vertex 2 moves along y
    GpuGeometry g = upload();
    EXPECT_EQ(g.keptPositions, groundFloats + 3 * 2 + 1);
    EXPECT_EQ(g.keptIndices, g.indices.size()) << "the body's topology did not change";
    std::swap(body.triangles[5][0], body.triangles[5][1]);  // a triangle turned over
    g = upload();
    EXPECT_EQ(g.keptPositions, g.positions.size());
    EXPECT_EQ(g.keptIndices, groundIndices + 3 * 5);
    // The cluster's origin is (0, 0, 0): a vertex x of +0 is sent as +0, of -0 as -0.
    body.vertices[0].x() = 0.0;
    g = upload();
    EXPECT_EQ(g.keptPositions, groundFloats);
    body.vertices[0].x() = -0.0;
    g = upload();
    ASSERT_TRUE(std::signbit(g.positions[groundFloats]));
    EXPECT_EQ(g.keptPositions, groundFloats) << "-0 was taken for the +0 the device holds";
    g = upload();
    EXPECT_EQ(g.keptPositions, g.positions.size());
}

}  // namespace
}  // namespace cullide::test
