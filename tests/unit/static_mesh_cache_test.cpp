// The static mesh cache (MeshCache.h), without GL: an entry kept until its mesh or transform changes, keys used
// twice in a frame, entries dropped when unused, rejections replayed in object order.
#include "MeshCache.h"
#include "MeshCacheSupport.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <limits>
#include <vector>

namespace cullide::test {
namespace {

using scenes::makeBox;

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
    objects[0].transform = &moved;  // a mesh with a transform: another mesh, and not static before its second frame
    const StaticLookup placed = lookUpAndCheck(cache, objects);
    EXPECT_EQ(placed.known[0], 0);
    EXPECT_EQ(placed.entry[0], nullptr);
    EXPECT_NE(placed.moving[0], nullptr);
    EXPECT_EQ(lookUpAndCheck(cache, objects).known[0], 1);
    Transform same = moved;  // another Transform with the same coefficients: the same entry
    objects[0].transform = &same;
    const StaticLookup kept = lookUpAndCheck(cache, objects);
    EXPECT_EQ(kept.known[0], 1);
    EXPECT_NE(kept.entry[0], nullptr);
    EXPECT_EQ(kept.moving[0], nullptr);
    kept.entry[0]->boxesReady = true;
    same.translation[2] = 1e-300;  // moved: its checks in its own frame hold, its world boxes do not
    const StaticLookup moving = lookUpAndCheck(cache, objects);
    EXPECT_EQ(moving.known[0], 1);
    EXPECT_EQ(moving.entry[0], nullptr);
    ASSERT_NE(moving.moving[0], nullptr);
    EXPECT_FALSE(moving.moving[0]->boxesReady);
    const StaticLookup rests = lookUpAndCheck(cache, objects);  // the same transform again: static once more
    EXPECT_EQ(rests.known[0], 1);
    EXPECT_NE(rests.entry[0], nullptr);
    EXPECT_EQ(rests.moving[0], nullptr);
    objects[0].transform = nullptr;  // the mesh now in world space: another mesh, under the same key
    EXPECT_EQ(lookUpAndCheck(cache, objects).known[0], 0);
}

namespace {

/// One frame through the cache and validation, as the culler runs them.
std::vector<ValidatedObject> validateFrame(StaticMeshCache& cache, const std::vector<Object>& objects, double margin,
                                           Result& result) {
    StaticLookup lookup;
    cache.lookUp(objects, lookup);
    std::vector<ValidatedObject> valid = validateObjects(objects, margin, result.rejected, nullptr, &lookup.known);
    StaticMeshCache::merge(objects, lookup, margin, valid, result, result.stats);
    return valid;
}

}  // namespace

TEST(StaticMeshCache, AFrameEndedBeforeMergeLeavesAMovingEntryConsistent) {
    const TriangleMesh box = makeBox(Vec3(1, 2, 3));
    Transform t;
    StaticMeshCache cache;
    const std::vector<Object> objects = {staticObject(box, 1, 1, &t)};
    for (int frame = 0; frame < 2; ++frame) {  // seen, then static
        Result result;
        validateFrame(cache, objects, 0.0, result);
    }
    t.translation = Vec3(4, 0, 0);
    StaticLookup abandoned;  // a frame that ends (an exception) between lookUp and merge
    cache.lookUp(objects, abandoned);
    Result result, fresh;
    const std::vector<ValidatedObject> valid = validateFrame(cache, objects, 0.0, result);
    const std::vector<ValidatedObject> expected = validateObjects(objects, 0.0, fresh.rejected);
    EXPECT_EQ(valid[0].box.min, expected[0].box.min) << "a box of the last transform placed";
    EXPECT_EQ(valid[0].box.max, expected[0].box.max);
}

TEST(StaticMeshCache, AMovingMeshIsPlacedByEachFramesTransform) {
    const TriangleMesh box = makeBox(Vec3(1, 2, 3));
    TriangleMesh broken = makeBox(Vec3::Ones());
    broken.vertices[2][0] = std::numeric_limits<double>::quiet_NaN();
    Transform t;
    t.translation = Vec3(10, 0, 0);
    Transform u = t;
    StaticMeshCache cache;
    std::vector<Object> objects = {staticObject(box, 1, 1, &t), staticObject(broken, 2, 1, &u)};
    const double margin = 0.25;
    for (int frame = 0; frame < 5; ++frame) {
        Result result;
        const std::vector<ValidatedObject> valid = validateFrame(cache, objects, margin, result);
        Result fresh;  // the same frame validated from scratch
        const std::vector<ValidatedObject> expected = validateObjects(objects, margin, fresh.rejected);
        EXPECT_EQ(result.stats.movingObjectsReused, frame == 0 ? 0u : 2u) << frame;
        ASSERT_EQ(result.rejected.size(), fresh.rejected.size()) << frame;
        for (std::size_t i = 0; i < result.rejected.size(); ++i) {
            EXPECT_EQ(result.rejected[i].object, fresh.rejected[i].object) << frame;
            EXPECT_EQ(result.rejected[i].message, fresh.rejected[i].message) << frame;
        }
        for (std::size_t i = 0; i < objects.size(); ++i) {
            EXPECT_EQ(valid[i].valid, expected[i].valid) << frame << " object " << i;
            EXPECT_EQ(valid[i].isMesh, expected[i].isMesh) << frame << " object " << i;
            EXPECT_EQ(valid[i].box.min, expected[i].box.min) << frame << " object " << i;
            EXPECT_EQ(valid[i].box.max, expected[i].box.max) << frame << " object " << i;
        }
        // Both move every frame; in frame 2 the first one's transform is not finite.
        t.linear = Eigen::AngleAxisd(0.4 * (frame + 1), Vec3(1, 2, 3).normalized()).toRotationMatrix();
        t.translation += Vec3(0.5, -0.25, 2.0);
        t.translation[1] = frame == 1 ? std::numeric_limits<double>::infinity() : 0.0;
        u.translation += Vec3(1, 1, 1);
    }
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

TEST(StaticMeshCache, AMovingKeyIsKeptWhileUsedAndCachedForItsFirstObjectOnly) {
    const TriangleMesh a = makeBox(Vec3::Ones());
    const TriangleMesh b = makeBox(Vec3::Constant(2.0));  // the same counts
    Transform t, u;
    StaticMeshCache cache;
    const std::vector<Object> objects = {staticObject(a, 3, 1, &t), staticObject(b, 3, 1, &u)};
    for (std::uint64_t frame = 0; frame < StaticMeshCache::kKeepFrames + 2; ++frame) {
        t.translation[0] = u.translation[1] = static_cast<double>(frame);  // both move every frame
        const StaticLookup lookup = lookUpAndCheck(cache, objects);
        ASSERT_NE(lookup.moving[0], nullptr) << frame;
        EXPECT_EQ(lookup.known[0], frame == 0 ? 0 : 1) << frame << ": dropped while in use";
        EXPECT_EQ(lookup.moving[1], nullptr) << frame << ": the second object with the key";
        EXPECT_EQ(lookup.entry[1], nullptr) << frame;
    }
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
        StaticMeshCache::merge(objects, lookup, 0.0, valid, result, result.stats);
        ASSERT_EQ(result.rejected.size(), 1u) << frame;
        EXPECT_EQ(result.rejected[0].object, 1u);
        EXPECT_FALSE(valid[1].valid);
        EXPECT_TRUE(valid[0].valid);
        EXPECT_EQ(result.stats.staticObjectsReused, frame == 0 ? 0u : 1u);
    }
}

}  // namespace
}  // namespace cullide::test
