// The device exact stage's float filter (DeviceExactFilter.h) against the exact predicates it stands in for: every
// pair it certifies intersecting intersects exactly, every pair it certifies apart is not within the margin by the
// CPU's test — on random pairs, near contacts a few ulps off, touching, coplanar and degenerate triangles, far from
// the origin — and it decides most pairs that are plainly apart or crossing (a filter that decides nothing is no
// filter).
#include "DeviceExact.h"
#include "DeviceExactFilter.h"
#include "TriangleCases.h"
#include "cullide/TriangleTest.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace cullide::test {
namespace {

/// What the filter said and what the exact predicates say, over many pairs.
struct Tally {
    std::size_t pairs = 0;
    std::size_t within = 0;   ///< certified intersecting
    std::size_t apart = 0;    ///< certified apart
    std::size_t wrong = 0;
    std::string firstWrong;
};

/// The filter's verdict on (a, b), given relative to `origin`: their world coordinates are origin + them, in double,
/// and the device holds world - origin rounded to float (devicePosition). Held to the exact predicates on the world
/// coordinates, as the CPU's exact stage runs them.
void check(const Tri& ra, const Tri& rb, double margin, const Vec3& origin, double bound, Tally& tally) {
    Tri a, b;
    float v[6][3];
    for (int k = 0; k < 3; ++k) {
        a[k] = origin + ra[k];
        b[k] = origin + rb[k];
        devicePosition(a[k], origin, v[k]);
        devicePosition(b[k], origin, v[3 + k]);
    }
    const FilterVerdict verdict = filterTrianglePair(v, exactReach(margin, origin, bound));
    ++tally.pairs;
    bool ok = true;
    if (verdict == FilterVerdict::Within) {
        ++tally.within;
        ok = trianglesIntersect(a[0], a[1], a[2], b[0], b[1], b[2]);
    } else if (verdict == FilterVerdict::Apart) {
        ++tally.apart;
        ok = !trianglesWithin(a[0], a[1], a[2], b[0], b[1], b[2], margin);
    }
    if (!ok && tally.wrong++ == 0)
        tally.firstWrong = (verdict == FilterVerdict::Within ? "certified intersecting: " : "certified apart: ") +
                           str(a) + " / " + str(b) + " margin " + std::to_string(margin);
}

Vec3 randomPoint(std::mt19937_64& rng, double scale) {
    std::uniform_real_distribution<double> u(-scale, scale);
    return {u(rng), u(rng), u(rng)};
}

Tri randomTriangle(std::mt19937_64& rng, const Vec3& centre, double size) {
    return {centre + randomPoint(rng, size), centre + randomPoint(rng, size), centre + randomPoint(rng, size)};
}

/// A point p moved off triangle t's plane by `offset` (along its normal), which may be a few ulps.
Vec3 offPlane(const Tri& t, const Vec3& p, double offset) {
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
    return p + offset * n;
}

TEST(DeviceExactFilter, RandomPairsAreDecidedMostlyAndNeverWrongly) {
    std::mt19937_64 rng(7);
    for (double margin : {0.0, 1e-3, 0.05}) {
        Tally tally;
        for (int i = 0; i < 20000; ++i) {
            const Tri a = randomTriangle(rng, Vec3::Zero(), 1.0);
            const Tri b = randomTriangle(rng, randomPoint(rng, 0.8), 1.0);
            check(a, b, margin, Vec3::Zero(), 2.0, tally);
        }
        EXPECT_EQ(tally.wrong, 0u) << tally.firstWrong;
        EXPECT_GT(tally.within, tally.pairs / 10) << "margin " << margin;
        EXPECT_GT(tally.apart, tally.pairs / 10) << "margin " << margin;
        EXPECT_GT(tally.within + tally.apart, tally.pairs * 9 / 10) << "margin " << margin << ": too few decided";
    }
}

TEST(DeviceExactFilter, NearContactsTouchingCoplanarAndDegenerateAreNeverDecidedWrongly) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (const Vec3& origin : {Vec3(0, 0, 0), Vec3(1e6, -3e6, 2e5), Vec3(3e11, 1e12, -7e11)}) {
        for (double margin : {0.0, 1e-6, 1e-2}) {
            Tally tally;
            for (int i = 0; i < 6000; ++i) {
                const double size = std::pow(10.0, -3.0 + 5.0 * unit(rng));
                const Tri a = randomTriangle(rng, Vec3::Zero(), size);
                // A point on a: inside (barycentric), on an edge, or a vertex.
                double u = unit(rng), w = unit(rng);
                if (u + w > 1.0) u = 1.0 - u, w = 1.0 - w;
                const int kind = i % 6;
                if (kind == 1) w = 0.0;
                if (kind == 2) u = w = 0.0;
                const Vec3 on = a[0] + u * (a[1] - a[0]) + w * (a[2] - a[0]);
                // b touches a there, or misses it by a few ulps to a few margins, across or beside its plane.
                const double gap = (kind == 3 ? 0.0 : std::pow(10.0, -16.0 + 15.0 * unit(rng))) * size;
                const Vec3 tip = offPlane(a, on, unit(rng) < 0.5 ? gap : -gap);
                Tri b = randomTriangle(rng, tip, size);
                b[0] = tip;
                if (kind == 4) b = {a[0], a[1] + (a[2] - a[1]) * unit(rng), tip};      // shares a vertex, coplanar-ish
                if (kind == 5) b = {tip, tip + (a[1] - a[0]) * 0.5, tip + (a[1] - a[0])};  // degenerate: a segment
                const double bound = 4.0 * size;
                check(a, b, margin, origin, bound, tally);
                // Coplanar: b's vertices in a's plane.
                const Tri flat = {on, on + (a[1] - a[0]) * unit(rng), on + (a[2] - a[0]) * unit(rng)};
                check(a, flat, margin, origin, bound, tally);
            }
            EXPECT_EQ(tally.wrong, 0u) << "origin " << origin.transpose() << ": " << tally.firstWrong;
            EXPECT_GT(tally.within + tally.apart, 0u);
        }
    }
}

TEST(DeviceExactFilter, AnAxisWhoseLengthUnderflowsCertifiesNothingWithAMargin) {
    // Nearly parallel edges whose tiny components lie in different axes: cross(r1, eb0) is about (0, -1e-23, -1e-23),
    // whose squared length underflows while the gap along it does not. The triangles are 10 apart: not apart by 20.
    const float v[6][3] = {{0.0f, 0.0f, 0.0f},   {1.0f, 1e-23f, 0.0f},   {0.5f, 1.0f, 0.0f},
                           {0.0f, -10.0f, 0.0f}, {1.0f, -10.0f, 1e-23f}, {0.5f, -15.0f, 0.0f}};
    EXPECT_NE(filterTrianglePair(v, 20.0f), FilterVerdict::Apart);
    // The same with components a device flushes (1e-40 squared is 0 there, and subnormal here).
    const float w[6][3] = {{0.0f, 0.0f, 0.0f},   {1.0f, 1e-20f, 0.0f},   {0.5f, 1.0f, 0.0f},
                           {0.0f, -20.0f, 0.0f}, {1.0f, -20.0f, 1e-20f}, {0.5f, -25.0f, 0.0f}};
    EXPECT_NE(filterTrianglePair(w, 40.0f), FilterVerdict::Apart);
}

}  // namespace
}  // namespace cullide::test
