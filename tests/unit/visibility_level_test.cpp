// The pure functions of the visibility level (VisibilityLevel.h), without GL: view fitting and its error bounds,
// owner packing, the survival rule, the device bounds of uploaded primitives.
#include "VisibilityLevel.h"
#include "bindings.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cullide::test {
namespace {

TEST(VisibilityLevel, ViewContainsTheBoundsGrownByHalfTheMargin) {
    Settings s;
    s.resolution = 64;
    s.margin = 0.2;
    const Aabb bounds{Vec3(-1, 0, 2), Vec3(3, 1, 2.5)};
    const View v = fitView(bounds, s, 0.0);
    for (int a = 0; a < 3; ++a) {
        EXPECT_LE(v.box.min[a], bounds.min[a] - 0.1) << a;
        EXPECT_GE(v.box.max[a], bounds.max[a] + 0.1) << a;
        EXPECT_LE(static_cast<double>(v.lo[a]), v.box.min[a] + 1e-6) << a;
        const double extent = v.box.extent()[a];
        EXPECT_NEAR(v.pixelScale[a], 64.0 / extent, 1e-5 * 64.0 / extent) << a;
        EXPECT_NEAR(v.depthScale[a], 1.0 / extent, 1e-5 / extent) << a;
        // Half a pixel plus the half margin in pixels, plus slack; the depth pad covers the half margin.
        EXPECT_GE(v.halfSize[a], 0.5 + 0.1 * 64.0 / extent) << a;
        EXPECT_LT(v.halfSize[a], 0.5 + 0.1 * 64.0 / extent + 0.01) << a;
        EXPECT_GE(v.depthPad[a], 0.1 / extent) << a;
        EXPECT_LT(v.depthPad[a], 0.1 / extent + 1e-3) << a;
    }
}

TEST(VisibilityLevel, FlatBoundsGetAThicknessAndFarCoordinatesMoreSlack) {
    Settings s;
    s.resolution = 256;
    const Aabb flat{Vec3(0, 0, 5), Vec3(1, 1, 5)};
    const View v = fitView(flat, s, 0.0);
    EXPECT_GT(v.box.extent()[2], 0.0);
    EXPECT_TRUE(std::isfinite(v.depthScale[2]));
    // The same box 1e6 from the upload origin: the float error of its coordinates grows, and so does the slack.
    const View near = fitView(Aabb{Vec3(0, 0, 0), Vec3(1, 1, 1)}, s, 1.0);
    const View far = fitView(Aabb{Vec3(0, 0, 0), Vec3(1, 1, 1)}, s, 1e6);
    for (int a = 0; a < 3; ++a) {
        EXPECT_GT(far.halfSize[a], near.halfSize[a]) << a;
        EXPECT_GT(far.depthPad[a], near.depthPad[a]) << a;
        // 2^-18 (1 + B / e) of the extent e: B = 1e6, so about 3.8 units whatever the extent.
        EXPECT_GT(far.halfSize[a] / far.pixelScale[a], 3.5f) << a;
        // Later iterations' bounds come from float vertices rounded to nearest: the view covers more than the half
        // ulp (1/32 at 1e6) by which a true vertex may lie outside.
        EXPECT_LE(far.box.min[a], -std::ldexp(1e6, -23)) << a;
        EXPECT_GE(far.box.max[a], 1.0 + std::ldexp(1e6, -23)) << a;
    }
}

TEST(VisibilityLevel, OwnerPackingAndSurvivalRule) {
    EXPECT_EQ(idBitsFor(0), 1u);
    EXPECT_EQ(idBitsFor(1), 1u);
    EXPECT_EQ(idBitsFor(2), 2u);
    EXPECT_EQ(idBitsFor(255), 8u);
    EXPECT_EQ(idBitsFor(256), 9u);
    EXPECT_EQ(idBitsFor(65535), 16u);
    EXPECT_EQ(depthBitsFor(1), 24u);
    EXPECT_EQ(depthBitsFor(16), 16u);
    EXPECT_EQ(requiredFlags(7), 0x3Fu);
    EXPECT_EQ(requiredFlags(1), 0x03u);
    EXPECT_EQ(requiredFlags(4), 0x30u);
    EXPECT_EQ(requiredFlags(5), 0x33u);
    LevelItems items;
    for (std::uint32_t o : {3u, 1u, 3u, 0u}) {
        items.owner.push_back(o);
        items.primBegin.push_back(0);
        items.bounds.push_back(Aabb{Vec3::Zero(), Vec3::Ones()});
    }
    EXPECT_EQ(distinctOwners(items), 3u);
    items.owner[0] = 70000;  // beyond 16 bits: the level prunes nothing
    EXPECT_EQ(distinctOwners(items), 0u);
    EXPECT_EQ(distinctOwners(LevelItems{}), 0u);
    // A level described by its objects: an owner per range (its items are not listed), its size the ranges' sum.
    LevelItems ranges;
    for (std::uint32_t o : {2u, 2u, 5u}) {
        ObjectRange r;
        r.itemBegin = static_cast<std::uint32_t>(ranges.objectItems);
        r.count = 10;
        r.owner = o;
        ranges.objectRanges.push_back(r);
        ranges.objectItems += r.count;
    }
    EXPECT_EQ(ranges.size(), 30u);
    EXPECT_EQ(distinctOwners(ranges), 2u);
    ranges.objectRanges.back().owner = 2;
    EXPECT_EQ(distinctOwners(ranges), 1u) << "one owner: nothing to collide with";
}

/// The boxes the views are fitted to are those of the primitives as uploaded: an item of two triangles, one of a
/// box, one of a triangle and a box.
TEST(VisibilityLevel, DeviceBoundsAreTheBoxesOfTheUploadedPrimitives) {
    GpuGeometry g;
    g.positions = {0.1f, -2.0f, 0.0f, 1.0f, 0.0f, 0.5f, 0.0f, 3.0f, -1e-30f, -4.0f, 0.25f, 7.0f};
    g.indices = {0, 1, 2, 1, 2, 3};
    g.boxes = {-1.0f, -1.0f, -1.0f, 0.5f, 0.5f, 1e30f};
    LevelItems items;
    items.owner = {0, 1, 2};
    items.primBegin = {0, 2, 3, 5};
    items.prims = {0, 1, CULLIDE_PRIM_BOX_BIT, 0, CULLIDE_PRIM_BOX_BIT};
    const Aabb a = deviceBoundsOf(g, items, 0), b = deviceBoundsOf(g, items, 1), c = deviceBoundsOf(g, items, 2);
    EXPECT_EQ(a.min, Vec3(-4.0, -2.0, double{-1e-30f}));
    EXPECT_EQ(a.max, Vec3(1.0, 3.0, 7.0));
    EXPECT_EQ(b.min, Vec3(-1.0, -1.0, -1.0));
    EXPECT_EQ(b.max, Vec3(0.5, 0.5, double{1e30f}));
    EXPECT_EQ(c.min, Vec3(-1.0, -2.0, -1.0));
    EXPECT_EQ(c.max, Vec3(1.0, 3.0, double{1e30f}));
}

/// The stop rule of a level's loop (stepAfter), which the device's chain (survive.comp) follows too: what ends a
/// level, in order, and an iteration that pruned too little of its items.
TEST(VisibilityLevel, StopRule) {
    Settings s;
    s.maxIterations = 4;
    s.minPruneFraction = 0.25;
    IterationResult r;
    r.ownerMin = 0;
    r.ownerMax = 3;
    r.alive = 60;  // of 100: 40 pruned
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Next);
    EXPECT_EQ(stepAfter(r, 100, 3, s), Step::Stop) << "the last iteration allowed";
    r.alive = 76;  // 24 pruned, under a quarter
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Stop);
    r.alive = 75;  // a quarter exactly: worth another
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Next);
    s.minPruneFraction = 0.0;
    r.alive = 99;
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Next) << "0: iterate while the set changes";
    r.alive = 100;
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Stop) << "the set did not change";
    r.alive = 50;
    r.overflows = 1;
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Stop) << "an overflow: the iteration pruned nothing";
    r.overflows = 0;
    r.ownerMax = 0;
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::AllPruned) << "one owner left";
    s.minPruneFraction = 1.0;
    EXPECT_EQ(stepAfter(r, 100, 3, s), Step::AllPruned) << "one owner left comes before the other rules";
    r.alive = 0;
    EXPECT_EQ(stepAfter(r, 100, 0, s), Step::Stop) << "none left";
}

}  // namespace
}  // namespace cullide::test
