// The mesh cache (static entries, the device's resident region) and the cluster upload built on it, without GL.
#include "ClusterGeometry.h"
#include "MeshCache.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide::test {
namespace {

using scenes::makeBox;
using scenes::transformMesh;

Object staticObject(const TriangleMesh& mesh, std::uint64_t key, std::uint64_t version = 1,
                    const Transform* transform = nullptr) {
    Object o;
    o.mesh = &mesh;
    o.staticKey = key;
    o.version = version;
    o.transform = transform;
    return o;
}

/// One frame's lookUp, with the entries marked checked as merge() would after validation.
StaticLookup lookUpAndCheck(StaticMeshCache& cache, const std::vector<Object>& objects) {
    StaticLookup lookup;
    cache.lookUp(objects, lookup);
    for (StaticEntry* e : lookup.entry)
        if (e != nullptr) e->checked = true;
    return lookup;
}

TEST(StaticMeshCache, KeepsAnEntryUntilItsMeshOrTransformChanges) {
    const TriangleMesh box = makeBox(Vec3::Ones());
    StaticMeshCache cache;
    std::vector<Object> objects = {staticObject(box, 7), Object{}};
    StaticLookup first = lookUpAndCheck(cache, objects);
    ASSERT_NE(first.entry[0], nullptr);
    EXPECT_EQ(first.entry[1], nullptr);  // no mesh: never cached
    EXPECT_EQ(first.known[0], 0);
    first.entry[0]->boxesReady = true;

    StaticLookup second = lookUpAndCheck(cache, objects);
    EXPECT_EQ(second.known[0], 1);
    EXPECT_TRUE(second.entry[0]->boxesReady);

    objects[0].version = 2;  // the caller changed the mesh
    StaticLookup third = lookUpAndCheck(cache, objects);
    EXPECT_EQ(third.known[0], 0);
    EXPECT_FALSE(third.entry[0]->boxesReady);

    Transform moved;
    moved.translation = Vec3(1, 0, 0);
    objects[0].transform = &moved;
    EXPECT_EQ(lookUpAndCheck(cache, objects).known[0], 0);
    EXPECT_EQ(lookUpAndCheck(cache, objects).known[0], 1);
    Transform same = moved;  // another Transform with the same coefficients: the same entry
    objects[0].transform = &same;
    EXPECT_EQ(lookUpAndCheck(cache, objects).known[0], 1);
    same.translation[2] = 1e-300;
    EXPECT_EQ(lookUpAndCheck(cache, objects).known[0], 0);
}

TEST(StaticMeshCache, AKeyUsedTwiceInOneFrameIsCachedForTheFirstOnly) {
    const TriangleMesh a = makeBox(Vec3::Ones());
    const TriangleMesh b = makeBox(Vec3::Constant(2.0));
    StaticMeshCache cache;
    const std::vector<Object> objects = {staticObject(a, 3), staticObject(b, 3)};
    const StaticLookup lookup = lookUpAndCheck(cache, objects);
    EXPECT_NE(lookup.entry[0], nullptr);
    EXPECT_EQ(lookup.entry[1], nullptr);
    EXPECT_EQ(cache.size(), 1u);
}

TEST(StaticMeshCache, DropsEntriesUnusedForKeepFrames) {
    const TriangleMesh box = makeBox(Vec3::Ones());
    StaticMeshCache cache;
    lookUpAndCheck(cache, {staticObject(box, 1), staticObject(box, 2)});
    for (std::uint64_t f = 0; f < StaticMeshCache::kKeepFrames; ++f) lookUpAndCheck(cache, {staticObject(box, 1)});
    EXPECT_EQ(cache.size(), 2u);  // key 2 last used kKeepFrames frames ago: still kept
    lookUpAndCheck(cache, {staticObject(box, 1)});
    EXPECT_EQ(cache.size(), 1u);
}

TEST(StaticMeshCache, MergeReplaysRejectionsInObjectOrder) {
    TriangleMesh broken = makeBox(Vec3::Ones());
    broken.triangles[0][1] = 99;
    const TriangleMesh box = makeBox(Vec3::Ones());
    StaticMeshCache cache;
    const std::vector<Object> objects = {staticObject(box, 0), staticObject(broken, 5)};
    for (int frame = 0; frame < 2; ++frame) {
        StaticLookup lookup;
        cache.lookUp(objects, lookup);
        Result result;
        std::vector<ValidatedObject> valid = validateObjects(objects, 0.0, result.rejected, nullptr, &lookup.known);
        StaticMeshCache::merge(lookup, valid, result, result.stats);
        ASSERT_EQ(result.rejected.size(), 1u) << frame;
        EXPECT_EQ(result.rejected[0].object, 1u);
        EXPECT_FALSE(valid[1].valid);
        EXPECT_TRUE(valid[0].valid);
        EXPECT_EQ(result.stats.staticObjectsReused, frame == 0 ? 0u : 1u);
    }
}

TEST(ResidentRegion, KeepsItsOriginWhileTheClusterStaysNearAndAlike) {
    ResidentRegion region;
    const Vec3 origin = region.fit(Vec3(10, 0, 0), 4.0, 1000);
    EXPECT_EQ(origin, Vec3(10, 0, 0));
    StaticEntry e;
    const ResidentRegion::Place first = region.place(e, 8, 12);
    EXPECT_TRUE(first.appended);
    EXPECT_EQ(first.baseTriangle, 0u);
    EXPECT_EQ(region.triangles(), 12u);
    // Moved by less than half the extent, same size: the region and the mesh in it stay.
    EXPECT_EQ(region.fit(Vec3(11.9, 0, 0), 4.0, 1000), origin);
    const ResidentRegion::Place again = region.place(e, 8, 12);
    EXPECT_FALSE(again.appended);
    EXPECT_EQ(again.baseTriangle, 0u);
    EXPECT_EQ(region.triangles(), 12u);
    // Each of these starts over: moved beyond half the extent, grown beyond 2x, shrunk below a quarter.
    for (const auto& [centre, extent] : std::vector<std::pair<Vec3, double>>{
             {Vec3(12.1, 0, 0), 4.0}, {Vec3(10, 0, 0), 8.1}, {Vec3(10, 0, 0), 0.9}}) {
        ResidentRegion r;
        r.fit(Vec3(10, 0, 0), 4.0, 1000);
        StaticEntry s;
        r.place(s, 8, 12);
        EXPECT_EQ(r.fit(centre, extent, 1000), centre) << centre.transpose() << " " << extent;
        EXPECT_EQ(r.triangles(), 0u);
        EXPECT_TRUE(r.place(s, 8, 12).appended);
    }
}

TEST(ResidentRegion, StartsOverWhenMostOfItIsStale) {
    ResidentRegion region;
    region.fit(Vec3::Zero(), 1.0, 0);
    std::vector<StaticEntry> entries(10);
    for (StaticEntry& e : entries) region.place(e, 10000, 20000);
    EXPECT_EQ(region.triangles(), 200000u);
    // 200,000 resident triangles, 70,000 of them still used: 200,000 <= 2 * 70,000 + 65,536 holds.
    region.fit(Vec3::Zero(), 1.0, 70000);
    EXPECT_EQ(region.triangles(), 200000u);
    // 60,000 used: 200,000 > 2 * 60,000 + 65,536, so the region is rebuilt and every mesh is written again.
    region.fit(Vec3::Zero(), 1.0, 60000);
    EXPECT_EQ(region.triangles(), 0u);
    EXPECT_TRUE(region.place(entries[3], 10000, 20000).appended);
}

/// Keeps what the culler hands to the device.
class RecordingBackend final : public PruningBackend {
public:
    std::vector<GpuGeometry> uploads;
    void upload(const GpuGeometry& geometry, Stats&) override { uploads.push_back(geometry); }
    void forgetUploads() override {}
    std::size_t deviceBytes() const override { return 0; }
    std::string renderer() const override { return "recording"; }
    std::string device() const override { return "none"; }
    void beginLevel(const LevelItems&, const View&, LevelStats&, Stats&) override {}
    IterationResult iterate(const View&, std::uint32_t, LevelStats&, Stats&) override { return {}; }
    void readAlive(std::vector<std::uint8_t>&, LevelStats&, Stats&) override {}
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
    EXPECT_EQ(second.keptPositions, 3 * ground.vertices.size());  // the ground stays on the device
    EXPECT_EQ(second.keptIndices, 3 * ground.triangles.size());
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

}  // namespace
}  // namespace cullide::test
