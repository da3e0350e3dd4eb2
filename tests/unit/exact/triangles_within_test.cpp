// trianglesWithin: whether two triangles are within a margin of each other, at and around the margin, symmetric,
// and the exact intersection test for a margin <= 0.
#include "TriangleCases.h"

#include <gtest/gtest.h>

namespace {

using cullide::trianglesWithin;
using namespace cullide::test;

TEST(TrianglesWithin, MarginBehaviour) {
    const Tri a = {V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
    const Tri b = {V(0.2, 0.2, 2), V(1.2, 0.2, 2), V(0.2, 1.2, 2)};  // distance 2 (parallel)
    auto within = [](const Tri& x, const Tri& y, double m) {
        const bool r = trianglesWithin(x[0], x[1], x[2], y[0], y[1], y[2], m);
        EXPECT_EQ(r, trianglesWithin(y[2], y[0], y[1], x[1], x[0], x[2], m)) << "asymmetric";
        return r;
    };
    EXPECT_FALSE(within(a, b, 0.0));
    EXPECT_FALSE(within(a, b, -5.0));
    EXPECT_FALSE(within(a, b, 1.9));
    EXPECT_TRUE(within(a, b, 2.0));
    EXPECT_TRUE(within(a, b, 2.1));
    EXPECT_FALSE(within(a, b, down(2.0)));
    // Far apart along x only: the box reject.
    const Tri far = {V(10, 0, 0), V(11, 0, 0), V(10, 1, 0)};
    EXPECT_FALSE(within(a, far, 8.9));
    EXPECT_TRUE(within(a, far, 9.0));
    // Intersecting pairs are within any margin; margin <= 0 is the exact test (touching counts).
    const Tri pierce = {V(0.2, 0.2, -1), V(0.2, 0.2, 1), V(0.5, 0.3, 1)};
    EXPECT_TRUE(within(a, pierce, 0.0));
    EXPECT_TRUE(within(a, pierce, 1e-9));
    const Tri touch = {V(1, 0, 0), V(2, 0, 0), V(2, 1, 0)};
    EXPECT_TRUE(within(a, touch, 0.0));
    EXPECT_TRUE(within(a, touch, -1.0));
    // Edge-edge gap of 0.25 (skew): tested by the distance, not the planes.
    const Tri skew = {V(0.25, -0.25, -1), V(0.25, -0.25, 1), V(0.25, -5, 0)};
    EXPECT_FALSE(within(a, skew, 0.2499));
    EXPECT_TRUE(within(a, skew, 0.2501));
    // Degenerate: a point above the face.
    const Tri pt = {V(0.25, 0.25, 0.5), V(0.25, 0.25, 0.5), V(0.25, 0.25, 0.5)};
    EXPECT_FALSE(within(a, pt, 0.4999));
    EXPECT_TRUE(within(a, pt, 0.5001));
}

}  // namespace
