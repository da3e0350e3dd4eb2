// The cache that keeps whole meshes' spatial orders between frames (TriangleOrders), without GL: shared by
// instances, only for active meshes that are wanted, recomputed when a mesh may have changed, unused ones dropped.
#include "TriangleOrders.h"
#include "TriangleRow.h"
#include "ValidatedObjects.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>
#include <numeric>
#include <tuple>
#include <vector>

namespace cullide::test {
namespace {

/// A frame in which every object is a valid, active mesh (what TriangleOrders::assign looks at).
FrameState activeFrame(std::size_t objects) {
    FrameState frame;
    frame.valid.assign(objects, validated(true, true, Aabb{}));
    frame.active.assign(objects, 1);
    return frame;
}

/// A new frame of `orders` for `objects`, with the orders of the meshes for which wanted(o) holds.
template <typename Wanted>
std::size_t nextFrame(TriangleOrders& orders, const std::vector<Object>& objects, FrameState& frame,
                      const Wanted& wanted, TaskPool& pool) {
    orders.beginFrame(objects.size(), frame);
    return orders.assign(objects, frame, wanted, pool);
}

/// One object per mesh, in world space.
std::vector<Object> meshObjects(std::initializer_list<const TriangleMesh*> meshes) {
    std::vector<Object> objects;
    for (const TriangleMesh* mesh : meshes) {
        objects.emplace_back();
        objects.back().mesh = mesh;
    }
    return objects;
}

/// Two world-space row meshes in an active frame, with a cache of orders and a pool of one worker.
struct TwoRows {
    TriangleMesh a = triangleRow(10);
    TriangleMesh b = triangleRow(20);
    std::vector<Object> objects = meshObjects({&a, &b});
    FrameState frame = activeFrame(2);
    TaskPool pool{1};
    TriangleOrders orders;
    auto parts() { return std::tie(objects, frame, pool, orders); }  ///< references to each part
};

TEST(TriangleOrders, KeptBetweenFramesAndSharedByInstances) {
    const TriangleMesh sphere = scenes::makeSphere(1.0, 20, 10);
    const TriangleMesh box = scenes::makeBox(Vec3::Ones());
    std::vector<Object> objects(3);
    objects[0].mesh = objects[1].mesh = &sphere;  // two instances
    objects[2].mesh = &box;
    TaskPool pool(2);
    TriangleOrders orders;
    FrameState frame = activeFrame(objects.size());
    auto all = [](std::uint32_t) { return true; };
    nextFrame(orders, objects, frame, all, pool);
    EXPECT_EQ(orders.computed(), 2u);
    ASSERT_NE(frame.order[0], nullptr);
    EXPECT_EQ(frame.order[0], frame.order[1]);
    std::vector<std::uint32_t> expected;
    spatialOrder(sphere, expected);
    EXPECT_EQ(*frame.order[0], expected);
    nextFrame(orders, objects, frame, all, pool);
    EXPECT_EQ(orders.computed(), 2u);  // the same meshes: nothing recomputed
    EXPECT_EQ(*frame.order[0], expected);
}

TEST(TriangleOrders, OnlyForActiveMeshesThatAreWanted) {
    const TriangleMesh box = scenes::makeBox(Vec3::Ones());
    const TriangleMesh other = scenes::makeBox(Vec3(1, 2, 3));
    const TriangleMesh third = scenes::makeBox(Vec3(3, 2, 1));
    std::vector<Object> objects(4);
    objects[0].mesh = &box;
    objects[1].mesh = &other;
    objects[2].mesh = &third;
    objects[3].box = Aabb{Vec3::Zero(), Vec3::Ones()};  // a box-only proxy
    FrameState frame = activeFrame(objects.size());
    frame.active[1] = 0;
    frame.valid[3].isMesh = false;
    TaskPool pool(2);
    TriangleOrders orders;
    nextFrame(orders, objects, frame, [](std::uint32_t o) { return o != 2; }, pool);
    EXPECT_NE(frame.order[0], nullptr);
    EXPECT_EQ(frame.order[1], nullptr);  // not active
    EXPECT_EQ(frame.order[2], nullptr);  // not wanted
    EXPECT_EQ(frame.order[3], nullptr);  // not a mesh
    EXPECT_EQ(orders.computed(), 1u);
}

TEST(TriangleOrders, RecomputedWhenTheMeshMayHaveChanged) {
    TriangleMesh moving = triangleRow(50);
    TriangleMesh fixed = triangleRow(60);
    std::vector<Object> objects(2);
    objects[0].mesh = &moving;
    objects[1].mesh = &fixed;
    objects[1].staticKey = 9;
    objects[1].version = 1;
    FrameState frame = activeFrame(objects.size());
    TaskPool pool(2);
    TriangleOrders orders;
    auto all = [](std::uint32_t) { return true; };
    auto framesUntilRecomputed = [&](std::size_t limit) {
        const std::uint64_t before = orders.computed();
        for (std::size_t f = 1; f <= limit; ++f) {
            nextFrame(orders, objects, frame, all, pool);
            if (orders.computed() != before) return f;
        }
        return limit + 1;
    };
    nextFrame(orders, objects, frame, all, pool);
    // Without a staticKey: within two refresh periods (the first one is staggered), then every period.
    objects.pop_back();
    frame = activeFrame(1);
    EXPECT_LE(framesUntilRecomputed(2 * TriangleOrders::kRefreshFrames), 2 * TriangleOrders::kRefreshFrames);
    EXPECT_EQ(framesUntilRecomputed(TriangleOrders::kRefreshFrames), TriangleOrders::kRefreshFrames);
    // A triangle more: at once.
    moving.triangles.push_back(moving.triangles.front());
    EXPECT_EQ(framesUntilRecomputed(1), 1u);
    EXPECT_EQ(frame.order[0]->size(), moving.triangles.size());
    objects = {Object{}};
    objects[0].mesh = &fixed;
    objects[0].staticKey = 9;
    objects[0].version = 1;
    // A static mesh (kept since the first frame, unused since): only when its version (or a count) changes.
    EXPECT_GT(framesUntilRecomputed(5 * TriangleOrders::kRefreshFrames), 5 * TriangleOrders::kRefreshFrames);
    objects[0].version = 2;
    EXPECT_EQ(framesUntilRecomputed(1), 1u);
}

TEST(TriangleOrders, InstancesWithKeysOfTheirOwnShareTheOrderAsUnkeyedOnesDo) {
    // Two moving instances of one mesh, each keyed (the Bullet adapter keys every body), the first in the frame
    // changing from frame to frame: the order is not recomputed for each, and a refresh that gives the same
    // permutation keeps its serial (what follows the order, a static mesh's place on the device, stays).
    TriangleMesh sphere = scenes::makeSphere(1.0, 20, 10);
    std::vector<Object> objects(2);
    objects[0].mesh = objects[1].mesh = &sphere;
    TaskPool pool(1);
    TriangleOrders orders;
    FrameState frame = activeFrame(objects.size());
    std::uint64_t firstSerial = 0;
    for (std::uint64_t f = 0; f < 2 * TriangleOrders::kRefreshFrames; ++f) {
        objects[0].staticKey = f % 2 == 0 ? 1 : 2;
        objects[1].staticKey = f % 2 == 0 ? 2 : 1;
        nextFrame(orders, objects, frame, [](std::uint32_t) { return true; }, pool);
        EXPECT_EQ(frame.orderSerial[0], frame.orderSerial[1]) << f;
        if (f == 0) firstSerial = frame.orderSerial[0];
    }
    EXPECT_LE(orders.computed(), 3u) << "recomputed for each instance in turn";
    EXPECT_GE(orders.computed(), 2u) << "an unkeyed use refreshes the order";
    EXPECT_NE(firstSerial, 0u);
    EXPECT_EQ(frame.orderSerial[0], firstSerial) << "the same permutation under a new serial";

    for (Vec3& v : sphere.vertices) v.x() += 0.5 * v.y() * v.y();  // bent in place: another permutation
    objects[0].version = objects[1].version = 1;
    const std::uint64_t before = orders.computed();
    for (std::uint64_t f = 0; f < 2 * TriangleOrders::kRefreshFrames && orders.computed() == before; ++f)
        nextFrame(orders, objects, frame, [](std::uint32_t) { return true; }, pool);
    std::vector<std::uint32_t> bent;
    spatialOrder(sphere, bent);
    ASSERT_EQ(*frame.order[0], bent);
    EXPECT_NE(frame.orderSerial[0], firstSerial) << "another permutation under the old serial";
}

TEST(TriangleOrders, AssignedTwiceInAFrameForDifferentMeshes) {
    // The CPU path asks for the whole trees' orders first, then for the survivors' trees: both stay set, and a mesh
    // asked for twice is not ordered twice.
    TwoRows rows;
    auto [objects, frame, pool, orders] = rows.parts();  // references into rows
    orders.beginFrame(objects.size(), frame);
    EXPECT_EQ(orders.assign(objects, frame, [](std::uint32_t o) { return o == 0; }, pool), 1u);
    EXPECT_EQ(orders.assign(objects, frame, [](std::uint32_t) { return true; }, pool), 1u);
    ASSERT_NE(frame.order[0], nullptr);
    ASSERT_NE(frame.order[1], nullptr);
    EXPECT_EQ(frame.order[1]->size(), rows.b.triangles.size());
    orders.beginFrame(objects.size(), frame);
    EXPECT_EQ(frame.order[0], nullptr) << "a new frame starts without orders";
}

TEST(TriangleOrders, UnusedOrdersAreDropped) {
    TwoRows rows;
    auto [objects, frame, pool, orders] = rows.parts();  // references into rows
    nextFrame(orders, objects, frame, [](std::uint32_t) { return true; }, pool);
    EXPECT_EQ(orders.size(), 2u);
    for (std::uint64_t f = 0; f <= TriangleOrders::kKeepFrames; ++f)
        nextFrame(orders, objects, frame, [](std::uint32_t o) { return o == 0; }, pool);
    EXPECT_EQ(orders.size(), 1u);
}

}  // namespace
}  // namespace cullide::test
