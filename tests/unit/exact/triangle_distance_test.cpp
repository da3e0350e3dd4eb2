// The distance between two triangles (triangleDistance): known distances for every contact kind, in all vertex
// orders of both triangles and with the triangles swapped, down to a gap of one ulp.
#include "TriangleCases.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace {

using cullide::Vec3;
using namespace cullide::test;

void expectDistance(const Tri& a, const Tri& b, double expected, const std::string& what) {
    SCOPED_TRACE(what);
    for (const auto& pa : kPerms) {
        for (const auto& pb : kPerms) {
            const Tri x = {a[pa[0]], a[pa[1]], a[pa[2]]}, y = {b[pb[0]], b[pb[1]], b[pb[2]]};
            EXPECT_NEAR(dist(x, y), expected, 1e-12 * std::max(1.0, expected));
            EXPECT_NEAR(dist(y, x), expected, 1e-12 * std::max(1.0, expected));
        }
    }
}

TEST(TriangleDistance, KnownDistances) {
    expectDistance({V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)}, {V(0.2, 0.2, 2), V(1.2, 0.2, 2), V(0.2, 1.2, 2)}, 2.0,
                   "parallel");
    expectDistance({V(-1, 0, 0), V(1, 0, 0), V(0, 0, -1)}, {V(0, -1, 3), V(0, 1, 3), V(0, 0, 4)}, 3.0,
                   "edge-edge skew");
    expectDistance({V(-1, 0, 0), V(1, 0, 0), V(0, 0, -1)}, {V(-1, -1, 3), V(1, 1, 3), V(0, 0, 5)}, 3.0,
                   "edge-edge skew at 45 degrees");
    expectDistance(kA, {V(1, 1, 2), V(1, 1, 5), V(2, 3, 7)}, 2.0, "vertex-face");
    expectDistance(kA, {V(5, 5, 0), V(6, 5, 0), V(5, 6, 0)}, 3.0 * std::sqrt(2.0), "coplanar vertex-edge");
    expectDistance(kA, {V(7, 0, 0), V(9, 0, 0), V(8, 1, 0)}, 3.0, "coplanar vertex-vertex");
    expectDistance(kA, {V(1, 1, -3), V(1, 1, -3), V(1, 1, -3)}, 3.0, "point-face");
    expectDistance({V(-1, 0, 0), V(1, 0, 0), V(0, 0, 0)}, {V(0, -1, 1), V(0, 1, 1), V(0, 1, 1)}, 1.0,
                   "segment-segment skew");
    expectDistance({V(1, 2, 3), V(1, 2, 3), V(1, 2, 3)}, {V(4, 6, 3), V(4, 6, 3), V(4, 6, 3)}, 5.0, "point-point");
    expectDistance(kA, {V(1, 1, -1), V(1, 1, 1), V(3, 3, 1)}, 0.0, "intersecting");
    // Sliver at a large offset: B's vertex 1e-3 above the sliver's interior.
    const Vec3 o(1e6, -1e6, 1e6);
    expectDistance({o + V(0, 0, 0), o + V(1, 0, 0), o + V(0.5, 0x1p-20, 0)},
                   {o + V(0.5, 0x1p-22, 0x1p-10), o + V(0.5, 0x1p-22, 1), o + V(0.75, 0.5, 1)}, 0x1p-10,
                   "sliver at an offset, vertex above its face");
    // Exact gaps of one ulp.
    const double z1 = up(1.0);
    const Tri a = {V(0, 0, 1), V(4, 0, 1), V(0, 4, 1)};
    EXPECT_EQ(dist(a, {V(1, 1, z1), V(5, 1, z1), V(1, 5, z1)}), z1 - 1.0);
}

}  // namespace
