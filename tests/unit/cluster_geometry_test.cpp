// The cluster upload (ClusterGeometry.h) built on the mesh cache, without GL: static meshes sent once, the others
// with every upload.
#include "ClusterGeometry.h"
#include "MeshCacheSupport.h"
#include "ValidatedObjects.h"
#include "WorldMeshes.h"
#include "cullide/scenes/Procedural.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

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
    std::vector<DeferredLevel> deferred;
    void beginFrame() override { deferred.clear(); }
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
    void pruneLevelDeferred(const LevelItems& items, const LevelStart&, std::size_t, Stats&,
                            std::vector<IterationTrace>*) override {
        DeferredLevel level;
        level.complete = true;
        level.survivors.assign(items.size(), 1);
        deferred.push_back(std::move(level));
    }
    bool collect(const Deadline&, std::vector<DeferredLevel>& results, Stats&) override {
        results.swap(deferred);
        deferred.clear();
        return true;
    }
};

TEST(ClusterGeometry, StaticMeshesAreSentOnceAndOthersEveryUpload) {
    const TriangleMesh ground = makeBox(Vec3(4, 4, 0.5));
    TriangleMesh body = makeBox(Vec3::Constant(0.5));
    transformMesh(body, Eigen::Affine3d(Eigen::Translation3d(0, 0, 0.9)));
    const std::vector<Object> objects = {staticObject(ground, 1), Object{}, staticObject(body, 0)};
    FrameState frame;
    frame.objects = &objects;
    frame.valid = {validated(true, true, {Vec3(-4, -4, -0.5), Vec3(4, 4, 0.5)}),
                   validated(true, false, {Vec3(3, 3, 0), Vec3(5, 5, 1)}),
                   validated(true, true, {Vec3(-0.5, -0.5, 0.4), Vec3(0.5, 0.5, 1.4)})};
    Cluster cluster;
    cluster.objects = {0, 1, 2};
    frame.allGroups = {Group{2, 0, 12, frame.valid[2].box, 0}};
    cluster.groups = frame.allGroups;
    StaticMeshCache cache;
    ClusterGeometry geometry;
    RecordingBackend backend;
    TaskPool pool(1);
    Stats stats;
    for (int f = 0; f < 2; ++f) {
        frame.statics = lookUpAndCheck(cache, objects);
        geometry.upload(frame, cluster, 0.0, backend, pool, stats);
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
    // Three object boxes, relative to the cluster's centre (0.5, 0.5, 0.45), rounded outwards, and the body's group
    // box after them, built on the device from its triangles (after the ground's in the spatial orders).
    ASSERT_EQ(second.boxes.size(), 3u * 6u);
    const auto groundTriangles = static_cast<std::uint32_t>(ground.triangles.size());
    EXPECT_EQ(second.builtRanges, (std::vector<std::uint32_t>{groundTriangles, 12}));
    EXPECT_EQ(geometry.objectBox(1), 1u);
    EXPECT_EQ(geometry.firstGroupBox(2), 3u);
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
    frame.valid = {validated(true, true, {Vec3(-4, -4, -0.5), Vec3(4, 4, 0.5)}),
                   validated(true, true, {Vec3(-0.5, -0.5, -0.5), Vec3(0.5, 0.5, 0.5)})};
    Cluster cluster;
    cluster.objects = {0, 1};
    StaticMeshCache cache;
    ClusterGeometry geometry;
    RecordingBackend backend;
    TaskPool pool(2);
    Stats stats;
    const auto upload = [&] {
        frame.statics = lookUpAndCheck(cache, objects);
        geometry.upload(frame, cluster, 0.0, backend, pool, stats);
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

/// A mesh that is not static keeps its place while others leave the cluster and come back (MeshSlots): the indices
/// and spatial orders the device holds stay valid, so only positions that changed are sent.
TEST(ClusterGeometry, MeshesKeepTheirPlacesWhileOthersComeAndGo) {
    std::vector<TriangleMesh> meshes = {makeBox(Vec3::Constant(0.5)), makeBox(Vec3::Constant(0.4)),
                                        makeBox(Vec3::Constant(0.3))};
    std::vector<Object> objects(3);
    FrameState frame;
    frame.objects = &objects;
    for (std::size_t i = 0; i < 3; ++i) {
        objects[i].mesh = &meshes[i];
        frame.valid.push_back(validated(true, true, {Vec3::Constant(-0.5), Vec3::Constant(0.5)}));
    }
    StaticMeshCache cache;
    ClusterGeometry geometry;
    RecordingBackend backend;
    TaskPool pool(1);
    Stats stats;
    std::vector<std::uint32_t> firstBase;
    for (const std::vector<std::uint32_t>& present : {std::vector<std::uint32_t>{0, 1, 2},
                                                      std::vector<std::uint32_t>{0, 2},
                                                      std::vector<std::uint32_t>{0, 1, 2}}) {
        frame.statics = lookUpAndCheck(cache, objects);
        Cluster cluster;
        cluster.objects = present;
        geometry.beginFrame();
        geometry.upload(frame, cluster, 0.0, backend, pool, stats);
        const GpuGeometry& g = backend.uploads.back();
        if (firstBase.empty()) {
            for (std::uint32_t o = 0; o < 3; ++o) firstBase.push_back(geometry.baseTriangle(o));
            continue;
        }
        for (std::uint32_t o : present) EXPECT_EQ(geometry.baseTriangle(o), firstBase[o]) << "object " << o;
        EXPECT_EQ(g.keptIndices, g.indices.size()) << present.size() << " objects: no index sent again";
        EXPECT_EQ(g.keptOrdered, g.ordered.size());
        EXPECT_EQ(g.keptPositions, g.positions.size()) << "nothing moved";
    }
}

/// The boxes hold every group of the cluster's static meshes (FrameState::allGroups), not only those the pre-pass
/// keeps, and the device builds every group's box of the other meshes after them (GpuGeometry::builtRanges, one range
/// of the spatial order each): when the kept set changes, no box moves and no range changes, so the device keeps them
/// (the GL back-end sends what changed). Each object's group boxes lie together (firstGroupBox).
TEST(ClusterGeometry, GroupBoxesStayInPlaceWhateverThePrepassKeeps) {
    const TriangleMesh a = makeBox(Vec3::Constant(0.5));
    TriangleMesh b = makeBox(Vec3::Constant(0.5));
    transformMesh(b, Eigen::Affine3d(Eigen::Translation3d(0.6, 0, 0)));
    std::vector<Object> objects = {staticObject(a, 7), Object{}};
    objects[1].mesh = &b;  // not static
    FrameState frame;
    frame.objects = &objects;
    frame.valid = {validated(true, true, {Vec3::Constant(-0.5), Vec3::Constant(0.5)}),
                   validated(true, true, {Vec3(0.1, -0.5, -0.5), Vec3(1.1, 0.5, 0.5)})};
    StaticMeshCache cache;
    // Three groups of four triangles per mesh, a box apiece that tells them apart.
    for (std::uint32_t k = 0; k < 6; ++k) {
        const std::uint32_t object = k < 3 ? 0 : 1;
        const double x = 0.1 * k;
        frame.allGroups.push_back({object, 4 * (k % 3), 4, {Vec3(x, 0, 0), Vec3(x + 0.05, 0.1, 0.1)}, k});
    }
    ClusterGeometry geometry;
    RecordingBackend backend;
    TaskPool pool(1);
    Stats stats;
    Cluster cluster;
    cluster.objects = {0, 1};
    std::vector<float> staticBoxes;
    for (const std::vector<std::uint32_t>& kept : {std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5},
                                                   std::vector<std::uint32_t>{1, 4}, std::vector<std::uint32_t>{5}}) {
        frame.statics = lookUpAndCheck(cache, objects);
        cluster.groups.clear();
        for (std::uint32_t k : kept) cluster.groups.push_back(frame.allGroups[k]);
        geometry.upload(frame, cluster, 0.25, backend, pool, stats);
        const GpuGeometry& g = backend.uploads.back();
        ASSERT_EQ(g.boxes.size(), 6u * (2 + 3)) << "two object boxes, the static mesh's every group's";
        if (staticBoxes.empty()) staticBoxes = g.boxes;
        EXPECT_EQ(g.boxes, staticBoxes) << "a static box moved when the pre-pass kept other groups";
        // The moving mesh's three groups, built: its triangles start after the static mesh's 12.
        EXPECT_EQ(g.builtRanges, (std::vector<std::uint32_t>{12, 4, 16, 4, 20, 4}));
        EXPECT_EQ(g.builtInflate, 0.125f);
        for (std::uint32_t k = 0; k < 6; ++k) {
            const std::uint32_t box = geometry.firstGroupBox(k < 3 ? 0 : 1) + k % 3;
            EXPECT_EQ(box, 2 + k) << "group " << k;
            if (k < 3) {
                EXPECT_NEAR(g.boxes[6 * box], 0.1 * k - g.origin.x(), 1e-6) << "group " << k;
            }
        }
    }
}

/// The CPU's copy of the boxes the device builds (allBoxes): each the box of its range's vertices grown by
/// builtInflate, after the uploaded ones; the first of equal coordinates stays (-0 before +0 stays -0).
TEST(ClusterGeometry, BuiltBoxesAreTheBoxesOfTheirTrianglesGrown) {
    GpuGeometry g;
    g.positions = {-0.0f, 0, 0, 1, 2, 3, 0.0f, -1, 5, 4, 4, 4};
    g.indices = {0, 1, 2, 1, 2, 3};
    g.ordered = {1, 0};
    g.boxes = {9, 9, 9, 9, 9, 9};
    g.builtRanges = {1, 1, 0, 2};  // triangle 0 alone, then both (triangle 1 first: the spatial order)
    g.builtInflate = 0.5f;
    const std::vector<float> all = allBoxes(g, g.positions);
    const std::vector<float> expected = {9, 9, 9, 9, 9, 9, -0.5f, -1.5f, -0.5f, 1.5f, 2.5f, 5.5f,
                                         -0.5f, -1.5f, -0.5f, 4.5f, 4.5f, 5.5f};
    EXPECT_EQ(all, expected);
    g.builtInflate = 0.0f;
    EXPECT_TRUE(std::signbit(allBoxes(g, g.positions)[6])) << "the first of -0 and +0 is kept";
    g.positions[0] = 0.0f;  // +0 first, then -0: +0 stays (no min or max, which may take either)
    g.positions[6] = -0.0f;
    EXPECT_FALSE(std::signbit(allBoxes(g, g.positions)[6]));
}

/// A mesh that came with a transform (and is not static) goes in its own frame: its own vertices are sent when they
/// change, its transform with every upload, and the positions mapped from them are its world twin's, bit for bit.
TEST(ClusterGeometry, AMeshWithATransformGoesInItsOwnFrameAndMapsToItsWorldTwin) {
    const TriangleMesh ground = makeBox(Vec3(4, 4, 0.5));
    const TriangleMesh local = makeBox(Vec3(0.5, 0.3, 0.2));
    Transform t;
    t.linear = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    t.translation = Vec3(0.1, -0.2, 0.9);
    TriangleMesh world = local;
    const std::vector<Object> inputs = {staticObject(ground, 1), Object{&local, &t, Aabb{}, 0, 0}};
    const std::vector<Object> twins = {inputs[0], Object{&world, nullptr, Aabb{}, 0, 0}};
    FrameState mappedFrame, twinFrame;
    mappedFrame.inputs = &inputs;
    mappedFrame.objects = &twins;  // the world meshes, as WorldMeshes resolves them
    twinFrame.inputs = &twins;
    twinFrame.objects = &twins;
    Cluster cluster;
    cluster.objects = {0, 1};
    StaticMeshCache mappedCache, twinCache;
    ClusterGeometry mappedGeometry, twinGeometry;
    RecordingBackend mappedBackend, twinBackend;
    TaskPool pool(2);
    Stats stats;
    for (int f = 0; f < 3; ++f) {
        Aabb localBox;
        for (std::size_t v = 0; v < local.vertices.size(); ++v) {
            world.vertices[v] = transformPoint(t, local.vertices[v]);
            localBox.grow(local.vertices[v]);
        }
        const std::vector<ValidatedObject> valid = {validated(true, true, {Vec3(-4, -4, -0.5), Vec3(4, 4, 0.5)}),
                                                    validated(true, true, transformedBounds(t, localBox))};
        mappedFrame.valid = valid;
        twinFrame.valid = valid;
        mappedFrame.statics = lookUpAndCheck(mappedCache, inputs);
        twinFrame.statics = lookUpAndCheck(twinCache, twins);
        mappedGeometry.upload(mappedFrame, cluster, 0.0, mappedBackend, pool, stats);
        twinGeometry.upload(twinFrame, cluster, 0.0, twinBackend, pool, stats);
        const GpuGeometry& m = mappedBackend.uploads.back();
        const GpuGeometry& w = twinBackend.uploads.back();
        ASSERT_EQ(m.mapped.size(), 1u);
        EXPECT_TRUE(w.mapped.empty());
        EXPECT_EQ(m.positions.size(), 3 * ground.vertices.size()) << "only the static ground in world space";
        EXPECT_EQ(m.local.size(), 3 * local.vertices.size());
        EXPECT_EQ(m.mapped[0].transform.translation, t.translation);
        EXPECT_EQ(m.indices, w.indices);
        // The body's place: after the ground, mapped (m) or not (w: its world twin).
        const std::vector<float> mapped = allPositions(m);
        const std::size_t groundFloats = 3 * ground.vertices.size(), bodyFloats = 3 * local.vertices.size();
        ASSERT_EQ(m.mapped[0].baseVertex, ground.vertices.size());
        ASSERT_EQ(mapped.size(), groundFloats + bodyFloats);
        ASSERT_GE(w.positions.size(), groundFloats + bodyFloats);
        EXPECT_EQ(std::memcmp(mapped.data(), w.positions.data(), 4 * mapped.size()), 0) << "frame " << f;
        if (f > 0) {
            EXPECT_EQ(m.keptLocal, m.local.size()) << "it moved rigidly: its own vertices stay on the device";
            EXPECT_EQ(m.keptPositions, m.positions.size());
            EXPECT_LT(w.keptPositions, w.positions.size()) << "its twin is sent again";
        }
        t.translation += Vec3(0.013, 0.021, -0.017);
        t.linear = Eigen::AngleAxisd(0.05, Vec3::UnitZ()).toRotationMatrix() * t.linear;
    }
}

}  // namespace
}  // namespace cullide::test
