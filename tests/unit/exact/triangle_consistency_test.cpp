// Seeded randomized consistency between the exact intersection test and the distance: intersecting iff at distance
// 0, 1-Lipschitz under translation, trianglesWithin agreeing with the distance, and the distance against dense
// sampling of both triangles.
#include "TriangleCases.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

namespace {

using cullide::trianglesIntersect;
using cullide::trianglesWithin;
using cullide::Vec3;
using namespace cullide::test;

Tri translated(const Tri& t, const Vec3& d) { return {t[0] + d, t[1] + d, t[2] + d}; }

/// Random triangles in the unit cube; every other pair is pushed towards contact.
Tri randomTri(std::mt19937_64& rng, double scale = 1.0) {
    std::uniform_real_distribution<double> u(-1, 1);
    return {V(u(rng), u(rng), u(rng)) * scale, V(u(rng), u(rng), u(rng)) * scale, V(u(rng), u(rng), u(rng)) * scale};
}

TEST(TriangleConsistency, IntersectIffDistanceZeroUpToContactTolerance) {
    std::mt19937_64 rng(20240611);
    std::uniform_real_distribution<double> u(-1, 1);
    int intersecting = 0, disjoint = 0, nearContact = 0;
    constexpr double kTol = 1e-12;  // absolute, for unit-size coordinates
    for (int n = 0; n < 20000; ++n) {
        const Tri a = randomTri(rng);
        Tri b = randomTri(rng, n % 4 == 0 ? 0.2 : 1.0);
        if (n % 2 == 1) b = translated(b, a[n % 3] - b[0] + 1e-3 * V(u(rng), u(rng), u(rng)));  // near contact
        const bool hit = trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
        const double d = dist(a, b);
        ASSERT_EQ(hit, d == 0.0) << str(a) << " | " << str(b);
        (hit ? intersecting : disjoint)++;
        nearContact += !hit && d < 1e-3;

        // 1-Lipschitz under translation: a pair the exact test calls intersecting is within |s| after a shift s, and a
        // pair at distance d cannot intersect after a shift shorter than d. Wrong answers in either direction break it.
        for (const double step : {1e-9, 1e-6, 1e-3, 1e-1}) {
            const Vec3 dir = V(u(rng), u(rng), u(rng)).normalized();
            const Tri moved = translated(b, step * dir);
            const bool hit2 = trianglesIntersect(a[0], a[1], a[2], moved[0], moved[1], moved[2]);
            const double d2 = dist(a, moved);
            ASSERT_LE(std::fabs(d2 - d), step + kTol) << "step " << step << ": " << str(a) << " | " << str(b);
            if (d > step + kTol) {
                ASSERT_FALSE(hit2) << "step " << step << ": " << str(a) << " | " << str(b);
            }
        }

        // trianglesWithin agrees with the distance away from the margin (relative 1e-9).
        const double m = std::fabs(u(rng)) * 0.5;
        if (std::fabs(d - m) > 1e-9) {
            ASSERT_EQ(trianglesWithin(a[0], a[1], a[2], b[0], b[1], b[2], m), d <= m) << "margin " << m << " d " << d;
        }
    }
    std::printf("[consistency] intersecting=%d disjoint=%d near-contact(<1e-3)=%d\n", intersecting, disjoint,
                nearContact);
    EXPECT_GT(intersecting, 1000);
    EXPECT_GT(disjoint, 1000);
    EXPECT_GT(nearContact, 100);
}

TEST(TriangleConsistency, DistanceMatchesDenseSampling) {
    // Upper bound: no sampled pair of points is closer than the distance. Lower bound: the densest sampling is
    // within its resolution of the distance.
    std::mt19937_64 rng(99);
    constexpr int kRes = 24;
    auto samples = [](const Tri& t) {
        std::vector<Vec3> s;
        for (int i = 0; i <= kRes; ++i) {
            for (int j = 0; i + j <= kRes; ++j) {
                const double x = double(i) / kRes, y = double(j) / kRes;
                s.push_back(t[0] + x * (t[1] - t[0]) + y * (t[2] - t[0]));
            }
        }
        return s;
    };
    for (int n = 0; n < 150; ++n) {
        const Tri a = randomTri(rng), b = translated(randomTri(rng), V(0.5, 0, 0));
        const double d = dist(a, b);
        const std::vector<Vec3> sa = samples(a), sb = samples(b);
        double best = std::numeric_limits<double>::infinity();
        for (const Vec3& p : sa) {
            for (const Vec3& q : sb) best = std::min(best, (p - q).squaredNorm());
        }
        best = std::sqrt(best);
        auto diam = [](const Tri& t) {
            return std::max({(t[0] - t[1]).norm(), (t[1] - t[2]).norm(), (t[2] - t[0]).norm()});
        };
        const double resolution = (diam(a) + diam(b)) / kRes;
        EXPECT_LE(d, best + 1e-12) << str(a) << " | " << str(b);
        EXPECT_GE(d, best - resolution) << str(a) << " | " << str(b);
    }
}

}  // namespace
