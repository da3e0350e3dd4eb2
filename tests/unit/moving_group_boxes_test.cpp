// The group boxes of a moving keyed mesh (TriangleSets.h, StaticLookup::moving): from its groups' boxes in its own
// frame, kept between frames and mapped by the frame's transform. Each must hold the world boxes of the group's
// triangles, whatever spatial order the group follows: boxes kept for another order (a new serial) are computed again.
#include "FrameState.h"
#include "TriangleOrders.h"
#include "TriangleSets.h"
#include "WorldMeshes.h"
#include "cullide/scenes/Procedural.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

namespace cullide::test {
namespace {

/// A frame of one moving keyed mesh (object 0, given in its own frame with `transform`) beside a box proxy that
/// covers it (object 1), with GPU levels: what buildTriangleBoxesAndGroups reads.
struct MovingMeshFrame {
    TriangleMesh local = scenes::makeSphere(1.0, 16, 8);
    TriangleMesh world;
    Transform transform;
    StaticEntry entry;
    std::vector<Object> inputs = std::vector<Object>(2);
    std::vector<Object> objects = std::vector<Object>(2);
    std::vector<std::uint32_t> order;
    FrameState frame;

    MovingMeshFrame() {
        transform.linear = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
        transform.translation = Vec3(5, -2, 1);
        world.triangles = local.triangles;
        for (const Vec3& v : local.vertices) world.vertices.push_back(transformPoint(transform, v));
        inputs[0].mesh = &local;
        inputs[0].transform = &transform;
        inputs[1].box = Aabb{Vec3::Constant(-100), Vec3::Constant(100)};
        objects = inputs;
        objects[0].mesh = &world;
        objects[0].transform = nullptr;
        frame.inputs = &inputs;
        frame.objects = &objects;
        frame.valid.resize(2);
        frame.valid[0].valid = frame.valid[0].isMesh = true;
        frame.valid[1].valid = true;
        frame.valid[1].box = inputs[1].box;
        frame.active = {1, 1};
        frame.partners = {{1}, {0}};
        frame.statics.entry = {nullptr, nullptr};
        frame.statics.moving = {&entry, nullptr};
        frame.gpuLevels = true;
    }

    /// The frame's groups with the spatial order `o` (serial `serial`).
    void build(const std::vector<std::uint32_t>& o, std::uint64_t serial, TaskPool& pool) {
        order = o;
        frame.order = {&order, nullptr};
        frame.orderSerial = {serial, 0};
        TriangleScratch scratch;
        Stats stats;
        buildTriangleBoxesAndGroups(frame, 8, 0.01, true, pool, scratch, stats);
    }

    /// Every group's box holds the world box of each of its triangles.
    void expectGroupsHoldTheirTriangles() const {
        ASSERT_EQ(frame.allGroups.size(), (world.triangles.size() + 7) / 8);
        for (const Group& g : frame.allGroups) {
            for (std::uint32_t k = g.first; k < g.first + g.count; ++k) {
                const Aabb t = triangleBounds(world, order[k], 0.005);
                EXPECT_TRUE((g.box.min.array() <= t.min.array()).all() && (g.box.max.array() >= t.max.array()).all())
                    << "group " << g.first / 8 << ", triangle " << order[k];
            }
        }
    }
};

TEST(MovingGroupBoxes, HoldTheirTrianglesInEverySpatialOrder) {
    TaskPool pool(2);
    MovingMeshFrame m;
    std::vector<std::uint32_t> first;
    spatialOrder(m.local, first);
    m.build(first, 1, pool);
    ASSERT_EQ(m.entry.localGroupBoxes.size(), m.frame.allGroups.size());
    m.expectGroupsHoldTheirTriangles();

    EXPECT_EQ(m.entry.groupOrder, 1u);

    m.transform.translation += Vec3(0.5, 0.25, 0);  // it moves: the kept boxes, mapped again
    for (std::size_t v = 0; v < m.local.vertices.size(); ++v)
        m.world.vertices[v] = transformPoint(m.transform, m.local.vertices[v]);
    const Aabb marked{Vec3::Constant(-50), Vec3::Constant(50)};  // a kept box the frame must not compute again
    m.entry.localGroupBoxes[0] = marked;
    m.build(first, 1, pool);
    m.expectGroupsHoldTheirTriangles();
    EXPECT_EQ(m.entry.localGroupBoxes[0].min, marked.min) << "kept boxes computed again under the same order";

    std::vector<std::uint32_t> second(first.rbegin(), first.rend());  // another order of the same mesh
    m.build(second, 2, pool);
    m.expectGroupsHoldTheirTriangles();
}

}  // namespace
}  // namespace cullide::test
