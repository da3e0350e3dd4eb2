// The exact orientation predicates (exact/ExactPredicates.h): sign conventions, zeros, subnormal and huge
// coordinates, and the filtered evaluation against the two exact ones on random, nearly degenerate inputs.
#include "TriangleCases.h"
#include "exact/ExactPredicates.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

namespace {

using cullide::Vec3;
using namespace cullide::test;

TEST(ExactPredicates, SignConventionsAndZeros) {
    using cullide::exact::orient2d;
    using cullide::exact::orient3d;
    EXPECT_EQ(orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, 1)), 1);
    EXPECT_EQ(orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, -1)), -1);
    EXPECT_EQ(orient3d(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(7, -3, 0)), 0);
    EXPECT_EQ(orient2d(0, 0, 1, 0, 0, 1), 1);
    EXPECT_EQ(orient2d(0, 0, 1, 0, 2, 0), 0);
    EXPECT_EQ(orient2d(0, 0, 1, 0, 0, -1), -1);
    // One ulp off the plane z = 1 at a large offset.
    const Vec3 o(1e7, 1e7, 1.0);
    EXPECT_EQ(orient3d(o, V(1e7 + 3, 1e7, 1.0), V(1e7, 1e7 + 5, 1.0), V(1e7 + 1, 1e7 + 1, up(1.0))), 1);
    EXPECT_EQ(orient3d(o, V(1e7 + 3, 1e7, 1.0), V(1e7, 1e7 + 5, 1.0), V(1e7 + 1, 1e7 + 1, down(1.0))), -1);
    EXPECT_EQ(orient3d(o, V(1e7 + 3, 1e7, 1.0), V(1e7, 1e7 + 5, 1.0), V(1e7 + 1, 1e7 + 1, 1.0)), 0);
    // Filter-defeating: a tilted plane through integer points, probed one ulp away along x.
    const Vec3 a(1, 2, 3), b(1001, 2, 4), c(1, 3003, 5);  // plane through a, b, c
    // Point on the plane: a + 0.5 (b - a) + 0.25 (c - a) (exact in binary).
    const Vec3 q = a + 0.5 * (b - a) + 0.25 * (c - a);
    EXPECT_EQ(orient3d(a, b, c, q), 0);
    const int sUp = orient3d(a, b, c, V(up(q.x()), q.y(), q.z()));
    const int sDown = orient3d(a, b, c, V(down(q.x()), q.y(), q.z()));
    EXPECT_NE(sUp, 0);
    EXPECT_EQ(sDown, -sUp);
    EXPECT_EQ(cullide::exact::orient3dExact(a.data(), b.data(), c.data(), q.data()), 0);
}

TEST(ExactPredicates, SubnormalAndHugeCoordinates) {
    using cullide::exact::orient2d;
    using cullide::exact::orient3d;
    const double t = std::numeric_limits<double>::denorm_min();
    const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
    EXPECT_EQ(orient3d(o, x, y, V(0.5, 0.5, t)), 1);
    EXPECT_EQ(orient3d(o, x, y, V(0.5, 0.5, -t)), -1);
    EXPECT_EQ(orient3d(o, x, y, V(0.5, 0.5, 0.0)), 0);
    // Mixed magnitudes: plane through (t, 0, 0), (1, t, 0), (0, 1, t) probed at points whose exact sign needs
    // products far below the subnormal range.
    const Vec3 p0(t, 0, 0), p1(1, t, 0), p2(0, 1, t);
    // det[(1 - t, t, 0), (-t, 1, t), (0.25 - t, 0.25, 0)] = -(1 - t) t / 4 + t^2 (0.25 - t) < 0 (by hand).
    const Vec3 q(0.25, 0.25, 0);
    EXPECT_EQ(orient3d(p0, p1, p2, q), -1);
    EXPECT_EQ(cullide::exact::orient3dExactBigInt(p0.data(), p1.data(), p2.data(), q.data()), -1);
    const double big = 0x1p+1000;
    EXPECT_EQ(orient3d(o, V(big, 0, 0), V(0, big, 0), V(1, 1, 0x1p-1000)), 1);
    EXPECT_EQ(orient3d(o, V(big, 0, 0), V(0, big, 0), V(1, 1, -t)), -1);
    EXPECT_EQ(orient3d(V(big, big, big), V(-big, big, big), V(big, -big, big), V(1e300, -1e300, big)), 0);
    EXPECT_EQ(orient3d(V(big, big, big), V(-big, big, big), V(big, -big, big), V(1e300, -1e300, up(big))), 1);
    const double h = 1e300;
    EXPECT_EQ(orient2d(0, 0, h, h, h, up(h)), 1);
    EXPECT_EQ(orient2d(0, 0, h, h, h, h), 0);
    EXPECT_EQ(orient2d(t, 0, 0, t, 2 * t, -t), 0);
    EXPECT_EQ(orient2d(t, 0, 0, t, 2 * t, 0), -1);  // (b - a) x (c - a) = (-t, t) x (t, 0) = -t^2
}

TEST(ExactPredicates, ExactMatchesFilterOnRandomInputs) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int n = 0; n < 20000; ++n) {
        Vec3 p[4];
        for (Vec3& v : p) v = V(u(rng), u(rng), u(rng));
        if (n % 2) {
            // Nearly coplanar, the rounded point in a random role: the plain floating-point sign is often wrong here.
            p[3] = p[0] + u(rng) * (p[1] - p[0]) + u(rng) * (p[2] - p[0]);
            std::rotate(p, p + (n / 2) % 4, p + 4);
        }
        const int f = cullide::exact::orient3d(p[0], p[1], p[2], p[3]);
        ASSERT_EQ(f, cullide::exact::orient3dExact(p[0].data(), p[1].data(), p[2].data(), p[3].data()));
        if (n % 16 == 1) {  // the two exact evaluations agree
            ASSERT_EQ(f, cullide::exact::orient3dExactBigInt(p[0].data(), p[1].data(), p[2].data(), p[3].data()));
        }
        // Antisymmetry under swapping two points, invariance under cyclic shifts of (a, b, c, d) with sign (-1).
        ASSERT_EQ(cullide::exact::orient3d(p[1], p[0], p[2], p[3]), -f);
        ASSERT_EQ(cullide::exact::orient3d(p[1], p[2], p[3], p[0]), -f);
        const int g = cullide::exact::orient2d(p[0].x(), p[0].y(), p[1].x(), p[1].y(), p[3].x(), p[3].y());
        ASSERT_EQ(g, cullide::exact::orient2dExact(p[0].x(), p[0].y(), p[1].x(), p[1].y(), p[3].x(), p[3].y()));
        ASSERT_EQ(cullide::exact::orient2d(p[1].x(), p[1].y(), p[3].x(), p[3].y(), p[0].x(), p[0].y()), g);
        const Vec3 e = p[0] + u(rng) * (p[1] - p[0]);  // nearly collinear in 2D
        ASSERT_EQ(cullide::exact::orient2d(p[1].x(), p[1].y(), e.x(), e.y(), p[0].x(), p[0].y()),
                  cullide::exact::orient2dExact(p[1].x(), p[1].y(), e.x(), e.y(), p[0].x(), p[0].y()));
    }
}

}  // namespace
