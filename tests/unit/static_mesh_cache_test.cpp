// The static mesh cache (MeshCache.h), without GL: an entry kept until its mesh or transform changes, keys used
// twice in a frame, entries dropped when unused, rejections replayed in object order.
#include "MeshCache.h"
#include "MeshCacheSupport.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace cullide::test
