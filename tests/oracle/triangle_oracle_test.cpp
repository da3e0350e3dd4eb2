// Property test of the exact triangle-triangle stage against CGAL (exact predicates kernel). This is the only file of
// the project that includes CGAL.
//
// Degenerate triangles are mapped to CGAL points/segments here (CGAL's Triangle_3 requires non-collinear vertices).
// Generators favour exact contact: small integer grids (so that vertices land exactly on the other triangle's plane,
// edges and vertices), coplanar pairs, shared vertices, degenerate triangles, large offsets and near-coplanar
// floating-point configurations that defeat the floating-point filter.
#include "cullide/TriangleTest.h"

#include "../../plugin/src/exact/ExactPredicates.h"

#include <Eigen/Geometry>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>

namespace {

using cullide::Vec3;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;
using S3 = K::Segment_3;
using T3 = K::Triangle_3;

P3 toCgal(const Vec3& v) { return P3(v.x(), v.y(), v.z()); }

bool lexLess(const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

/// A closed triangle as CGAL sees it: a point, a segment or a proper triangle.
struct Shape {
    enum Kind { kPoint, kSegment, kTriangle } kind;
    P3 p[3];
};

Shape toShape(const Vec3& a, const Vec3& b, const Vec3& c) {
    Shape s{};
    const P3 pa = toCgal(a), pb = toCgal(b), pc = toCgal(c);
    if (a == b && b == c) {
        s.kind = Shape::kPoint;
        s.p[0] = pa;
        return s;
    }
    if (CGAL::collinear(pa, pb, pc)) {
        // On a line the lexicographic order is monotone, so its extremes are the segment's end points.
        const Vec3* v[3] = {&a, &b, &c};
        std::sort(v, v + 3, [](const Vec3* x, const Vec3* y) { return lexLess(*x, *y); });
        s.kind = Shape::kSegment;
        s.p[0] = toCgal(*v[0]);
        s.p[1] = toCgal(*v[2]);
        return s;
    }
    s.kind = Shape::kTriangle;
    s.p[0] = pa;
    s.p[1] = pb;
    s.p[2] = pc;
    return s;
}

bool cgalIntersect(const Shape& x, const Shape& y) {
    if (x.kind > y.kind) return cgalIntersect(y, x);
    switch (x.kind) {
        case Shape::kPoint:
            switch (y.kind) {
                case Shape::kPoint: return x.p[0] == y.p[0];
                case Shape::kSegment: return CGAL::do_intersect(x.p[0], S3(y.p[0], y.p[1]));
                case Shape::kTriangle: return CGAL::do_intersect(x.p[0], T3(y.p[0], y.p[1], y.p[2]));
            }
            break;
        case Shape::kSegment:
            if (y.kind == Shape::kSegment) return CGAL::do_intersect(S3(x.p[0], x.p[1]), S3(y.p[0], y.p[1]));
            return CGAL::do_intersect(S3(x.p[0], x.p[1]), T3(y.p[0], y.p[1], y.p[2]));
        case Shape::kTriangle:
            return CGAL::do_intersect(T3(x.p[0], x.p[1], x.p[2]), T3(y.p[0], y.p[1], y.p[2]));
    }
    return false;
}

using Pair = std::array<Vec3, 6>;

enum Category {
    kRandom,
    kGrid,
    kCoplanar,
    kSnappedToPlane,
    kSharedVertex,
    kDegenerate,
    kNearCoplanarFloat,
    kOffsetTiny,
    kExtremeMagnitudes,
    kCategoryCount
};

const char* kCategoryNames[kCategoryCount] = {"random",         "integer-grid",  "coplanar",
                                              "snapped-to-plane", "shared-vertex", "degenerate",
                                              "near-coplanar-float", "offset-tiny",
                                              "extreme-magnitudes"};

class Generator {
public:
    explicit Generator(std::uint64_t seed) : rng_(seed) {}

    int intIn(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
    double real(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
    bool coin(double p = 0.5) { return std::bernoulli_distribution(p)(rng_); }
    Vec3 randomUnitCube() { return {real(-1, 1), real(-1, 1), real(-1, 1)}; }
    Vec3 gridPoint(int r) { return {double(intIn(-r, r)), double(intIn(-r, r)), double(intIn(-r, r))}; }

    /// Exact similarity on integer-valued points: scale by a power of two and add an integer offset (in scale
    /// units), all representable, so exact contacts survive.
    void scaleAndOffset(Pair& p) {
        const double scale = std::ldexp(1.0, intIn(-20, 20));
        Vec3 offset = Vec3::Zero();
        if (coin(0.5)) {
            const double mag = std::ldexp(1.0, intIn(0, 23));
            offset = Vec3(std::round(real(-mag, mag)), std::round(real(-mag, mag)), std::round(real(-mag, mag)));
        }
        for (Vec3& v : p) v = (v + offset) * scale;
    }

    Pair make(Category c) {
        Pair p;
        switch (c) {
            case kRandom:
                for (Vec3& v : p) v = randomUnitCube();
                break;
            case kGrid: {
                const int r = intIn(1, 3);
                for (Vec3& v : p) v = gridPoint(r);
                scaleAndOffset(p);
                break;
            }
            case kCoplanar: {
                const Vec3 o = gridPoint(4), u = gridPoint(3), w = gridPoint(3);
                for (Vec3& v : p) v = o + double(intIn(-3, 3)) * u + double(intIn(-3, 3)) * w;
                scaleAndOffset(p);
                break;
            }
            case kSnappedToPlane: {
                for (int i = 0; i < 3; ++i) p[i] = gridPoint(8);
                for (int i = 3; i < 6; ++i) {
                    if (coin(0.7)) {
                        // a0 + (s/2)(a1 - a0) + (t/2)(a2 - a0): vertices, edge midpoints, interior and outside points.
                        const double s = 0.5 * intIn(-1, 3), t = 0.5 * intIn(-1, 3);
                        p[i] = p[0] + s * (p[1] - p[0]) + t * (p[2] - p[0]);
                    } else {
                        p[i] = gridPoint(8);
                    }
                }
                scaleAndOffset(p);
                break;
            }
            case kSharedVertex: {
                const bool grid = coin();
                for (Vec3& v : p) v = grid ? gridPoint(3) : randomUnitCube();
                const int shared = intIn(1, 2);
                int copied = 0;
                for (int k = 0; k < shared; ++k) p[3 + (copied = intIn(0, 2))] = p[intIn(0, 2)];
                if (grid) scaleAndOffset(p);
                if (coin(0.4)) {
                    // Nudge the (last) shared vertex by one ulp in one coordinate: a near-miss at the vertex.
                    double& x = p[3 + copied][intIn(0, 2)];
                    x = std::nextafter(x, coin() ? HUGE_VAL : -HUGE_VAL);
                }
                break;
            }
            case kDegenerate: {
                const bool grid = coin();
                for (Vec3& v : p) v = grid ? gridPoint(2) : randomUnitCube();
                const int which = intIn(0, 2);  // A, B or both degenerate
                for (int t = 0; t < 2; ++t) {
                    if (!(which == 2 || which == t)) continue;
                    Vec3* tri = &p[3 * t];
                    switch (intIn(0, 2)) {
                        case 0:  // point
                            tri[1] = tri[0];
                            tri[2] = tri[0];
                            break;
                        case 1:  // repeated vertex
                            tri[intIn(1, 2)] = tri[0];
                            break;
                        default: {  // collinear, exactly representable
                            const Vec3 d = grid ? gridPoint(2) : Vec3(std::ldexp(real(-1, 1), -2),
                                                                      std::ldexp(real(-1, 1), -2),
                                                                      std::ldexp(real(-1, 1), -2));
                            tri[1] = tri[0] + double(intIn(-2, 2)) * d;
                            tri[2] = tri[0] + double(intIn(-2, 2)) * d;
                            break;
                        }
                    }
                }
                if (grid) scaleAndOffset(p);
                break;
            }
            case kNearCoplanarFloat: {
                for (int i = 0; i < 3; ++i) p[i] = randomUnitCube();
                const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]);
                for (int i = 3; i < 6; ++i) {
                    // Rounded barycentric combinations: on the plane up to rounding, often near edges/vertices.
                    double s = real(-0.5, 1.5), t = real(-0.5, 1.5);
                    if (coin(0.3)) s = 0.0;
                    if (coin(0.3)) t = 1.0 - s;
                    p[i] = p[0] + s * (p[1] - p[0]) + t * (p[2] - p[0]);
                    if (coin(0.3)) p[i] += n * std::ldexp(real(-1, 1), -intIn(40, 60));
                }
                break;
            }
            case kOffsetTiny: {
                const double size = std::pow(10.0, real(-9, -3));
                const Vec3 offset = Vec3(real(-1, 1), real(-1, 1), real(-1, 1)) * std::pow(10.0, real(5, 7));
                for (Vec3& v : p) v = offset + size * randomUnitCube();
                if (coin()) {
                    // B is a perturbed copy of A: nearly coplanar and overlapping.
                    for (int i = 0; i < 3; ++i) p[3 + i] = p[i] + size * 1e-6 * randomUnitCube();
                }
                break;
            }
            case kExtremeMagnitudes: {
                // Subnormal, tiny and huge coordinates: the exact stage must switch to big integers.
                const int mode = intIn(0, 2);
                if (mode == 0) {
                    // An integer grid scaled into the subnormal range or close to overflow (exact).
                    for (Vec3& v : p) v = gridPoint(2);
                    const double scale = coin() ? std::ldexp(1.0, intIn(-1074, -1040)) : std::ldexp(1.0, intIn(900, 1000));
                    for (Vec3& v : p) v *= scale;
                } else {
                    // Unit-cube or grid points with some coordinates replaced by tiny/subnormal/huge values, zeros,
                    // or nudged off zero by one subnormal step.
                    const bool grid = coin();
                    for (Vec3& v : p) v = grid ? gridPoint(2) : randomUnitCube();
                    for (Vec3& v : p) {
                        for (int k = 0; k < 3; ++k) {
                            if (!coin(0.3)) continue;
                            switch (intIn(0, 3)) {
                                case 0: v[k] = std::ldexp(real(-1, 1), -intIn(1000, 1074)); break;
                                case 1: v[k] = std::ldexp(real(-1, 1), -intIn(300, 900)); break;
                                case 2: v[k] = 0.0; break;
                                default: v[k] = std::nextafter(0.0, coin() ? 1.0 : -1.0); break;
                            }
                        }
                    }
                    if (mode == 2) {
                        // Huge but exactly scaled copies: contact structure kept, magnitudes near 2^1000.
                        const double scale = std::ldexp(1.0, intIn(600, 1000));
                        for (Vec3& v : p) v *= scale;
                    }
                }
                break;
            }
            default:
                break;
        }
        // Random vertex order and random triangle order.
        int perm[3] = {0, 1, 2};
        std::shuffle(perm, perm + 3, rng_);
        const Pair q = p;
        for (int i = 0; i < 3; ++i) p[i] = q[perm[i]];
        std::shuffle(perm, perm + 3, rng_);
        for (int i = 0; i < 3; ++i) p[3 + i] = q[3 + perm[i]];
        if (coin()) std::swap_ranges(p.begin(), p.begin() + 3, p.begin() + 3);
        return p;
    }

    std::mt19937_64& rng() { return rng_; }

private:
    std::mt19937_64 rng_;
};

std::string formatPair(const Pair& p) {
    std::string s;
    char buf[160];
    for (int i = 0; i < 6; ++i) {
        std::snprintf(buf, sizeof buf, "%s{%a, %a, %a}", i == 3 ? " | " : (i ? ", " : ""), p[i].x(), p[i].y(),
                      p[i].z());
        s += buf;
    }
    return s;
}

TEST(TriangleOracle, MatchesCgalOnOneMillionAdversarialPairs) {
    constexpr int kPerCategory = 125000;
    Generator gen(0xC0111DE5EEDull);
    cullide::exact::resetExactFallbackCount();
    std::uint64_t hits[kCategoryCount] = {}, mismatches[kCategoryCount] = {}, fallbacks[kCategoryCount] = {};
    std::uint64_t degenerate = 0, total = 0;
    double oursSeconds = 0.0;
    int printed = 0;
    const auto start = std::chrono::steady_clock::now();
    for (int c = 0; c < kCategoryCount; ++c) {
        const std::uint64_t fallbacksBefore = cullide::exact::exactFallbackCount();
        for (int n = 0; n < kPerCategory; ++n) {
            const Pair p = gen.make(static_cast<Category>(c));
            const auto t0 = std::chrono::steady_clock::now();
            const bool ours = cullide::trianglesIntersect(p[0], p[1], p[2], p[3], p[4], p[5]);
            oursSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const Shape sa = toShape(p[0], p[1], p[2]), sb = toShape(p[3], p[4], p[5]);
            degenerate += (sa.kind != Shape::kTriangle) + (sb.kind != Shape::kTriangle);
            const bool expected = cgalIntersect(sa, sb);
            hits[c] += expected;
            ++total;
            if (ours != expected) {
                ++mismatches[c];
                if (printed++ < 10) {
                    ADD_FAILURE() << kCategoryNames[c] << ": ours=" << ours << " cgal=" << expected << " for "
                                  << formatPair(p);
                }
            }
        }
        fallbacks[c] = cullide::exact::exactFallbackCount() - fallbacksBefore;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("[oracle] %llu pairs in %.2f s (trianglesIntersect: %.1f ns/call incl. timer), %llu degenerate "
                "triangles\n",
                static_cast<unsigned long long>(total), seconds, 1e9 * oursSeconds / double(total),
                static_cast<unsigned long long>(degenerate));
    for (int c = 0; c < kCategoryCount; ++c) {
        std::printf("[oracle]   %-20s cases=%d intersecting=%llu exact-fallback-predicates=%llu mismatches=%llu\n",
                    kCategoryNames[c], kPerCategory, static_cast<unsigned long long>(hits[c]),
                    static_cast<unsigned long long>(fallbacks[c]), static_cast<unsigned long long>(mismatches[c]));
        EXPECT_EQ(mismatches[c], 0u) << kCategoryNames[c];
        // Each category must exercise both answers, or it tests nothing.
        EXPECT_GT(hits[c], 0u) << kCategoryNames[c];
        EXPECT_LT(hits[c], static_cast<std::uint64_t>(kPerCategory)) << kCategoryNames[c];
    }
    EXPECT_GT(total, 999999u);
}

/// The predicates themselves against CGAL's exact orientation, on inputs that defeat the filter.
TEST(TriangleOracle, PredicatesMatchCgalOrientation) {
    Generator gen(0x0123456789ull);
    cullide::exact::resetExactFallbackCount();
    int mismatches3 = 0, mismatches2 = 0, zeros3 = 0, zeros2 = 0;
    constexpr int kCases = 200000;
    for (int n = 0; n < kCases; ++n) {
        Vec3 a, b, c, d;
        const int kind = n % 4;
        if (kind == 0 || kind == 3) {
            // Near-coplanar unit-cube points, the rounded combination in a random role: the plain floating-point
            // determinant has the wrong sign in about a third of these.
            a = gen.randomUnitCube();
            b = gen.randomUnitCube();
            c = gen.randomUnitCube();
            d = a + gen.real(-1, 1) * (b - a) + gen.real(-1, 1) * (c - a);
            for (int r = gen.intIn(0, 3); r > 0; --r) {
                const Vec3 t = a;
                a = b;
                b = c;
                c = d;
                d = t;
            }
            if (kind == 3) {
                // Extreme magnitudes: scaled towards underflow or overflow, some coordinates subnormal or zero.
                const double scale = std::ldexp(1.0, gen.coin() ? gen.intIn(-1060, -900) : gen.intIn(900, 1020));
                for (Vec3* v : {&a, &b, &c, &d}) {
                    *v *= scale;
                    if (gen.coin(0.3)) (*v)[gen.intIn(0, 2)] = gen.coin() ? 0.0 : std::ldexp(gen.real(-1, 1), -1070);
                }
            }
        } else if (kind == 1) {
            // Near-coplanar floats at an offset: d is a rounded affine combination of a, b, c, nudged by a few ulps.
            a = gen.randomUnitCube() * std::pow(10.0, gen.real(-3, 7));
            b = a + gen.randomUnitCube();
            c = a + gen.randomUnitCube();
            const double s = gen.real(-2, 2), t = gen.real(-2, 2);
            d = a + s * (b - a) + t * (c - a);
            for (int k = 0; k < 3; ++k) {
                const int nudges = gen.intIn(-2, 2);
                for (int m = 0; m < std::abs(nudges); ++m) {
                    d[k] = std::nextafter(d[k], nudges > 0 ? HUGE_VAL : -HUGE_VAL);
                }
            }
        } else {
            // Integer configurations: many exact zeros.
            a = gen.gridPoint(4);
            b = gen.gridPoint(4);
            c = gen.gridPoint(4);
            d = a + double(gen.intIn(-2, 2)) * (b - a) + double(gen.intIn(-2, 2)) * (c - a) +
                (gen.coin() ? gen.gridPoint(1) : Vec3::Zero());
            const double scale = std::ldexp(1.0, gen.intIn(-30, 30));
            a *= scale;
            b *= scale;
            c *= scale;
            d *= scale;
        }
        const int ours3 = cullide::exact::orient3d(a, b, c, d);
        const int exact3 = cullide::exact::orient3dExact(a.data(), b.data(), c.data(), d.data());
        const int cgal3 = static_cast<int>(CGAL::orientation(toCgal(a), toCgal(b), toCgal(c), toCgal(d)));
        zeros3 += cgal3 == 0;
        if (ours3 != cgal3 || exact3 != cgal3) {
            if (mismatches3++ < 5) {
                ADD_FAILURE() << "orient3d " << ours3 << "/" << exact3 << " vs cgal " << cgal3 << " for "
                              << formatPair({a, b, c, d, d, d});
            }
        }
        // orient2d on the (x, y) projection; for kind 0 with a near-collinear third point.
        Vec3 e = d;
        if (kind == 0) e = a + gen.real(-2, 2) * (b - a);
        if (kind == 2 && gen.coin()) e = a + double(gen.intIn(-2, 2)) * (b - a);
        const int ours2 = cullide::exact::orient2d(a.x(), a.y(), b.x(), b.y(), e.x(), e.y());
        const int exact2 = cullide::exact::orient2dExact(a.x(), a.y(), b.x(), b.y(), e.x(), e.y());
        const int cgal2 = static_cast<int>(
            CGAL::orientation(K::Point_2(a.x(), a.y()), K::Point_2(b.x(), b.y()), K::Point_2(e.x(), e.y())));
        zeros2 += cgal2 == 0;
        if (ours2 != cgal2 || exact2 != cgal2) {
            if (mismatches2++ < 5) {
                ADD_FAILURE() << "orient2d " << ours2 << "/" << exact2 << " vs cgal " << cgal2 << " for "
                              << formatPair({a, b, e, a, b, e});
            }
        }
    }
    std::printf("[oracle] predicates: %d cases, %d exact-zero orient3d, %d exact-zero orient2d, %llu filter "
                "failures\n",
                kCases, zeros3, zeros2, static_cast<unsigned long long>(cullide::exact::exactFallbackCount()));
    EXPECT_EQ(mismatches3, 0);
    EXPECT_EQ(mismatches2, 0);
    EXPECT_GT(zeros3, kCases / 10);
    EXPECT_GT(zeros2, kCases / 100);
}

}  // namespace
