// The device exact stage's floating-point filter (shaders/exact.comp), on the CPU, float for float: the reference
// backend runs it and the GL tests hold the device to it. It decides a candidate triangle pair from the six vertices
// as the device holds them (float, relative to the upload origin) where it can certify the answer of the CPU's exact
// predicate (candidateWithin) — apart, or intersecting — and leaves every other pair to that predicate.
//
// Certified, with every error bounded (docs/reliability.md §8):
// - a device coordinate is within 2^-23 |p| + 2^-125 of the true one (double, relative to the origin: rounding to
//   float, a flushed denormal);
// - Apart: along one of 11 axes (both normals, the 9 edge-edge cross products, as computed: any axis bounds the
//   distance from below) the two projections are farther apart than `reach` times the axis length, after the
//   projections' error bound is taken off. `reach` is the margin plus the double distance's own error, rounded up
//   (0 for margin 0: the CPU's test is then exact intersection).
// - Intersecting: an edge of one triangle crosses the other's plane strictly between its ends and passes strictly
//   inside it — five orientation signs, each certified by a static error bound of the 3x3 determinant with its
//   inputs' error.
// Only +, -, * (correctly rounded in GLSL 4.5) and comparisons; no sqrt, no division, no fused operation (the shader
// marks every value `precise`, and the C++ build contracts none). NaN or overflow lands in Uncertain. A device may
// flush subnormal values to zero: the error bounds carry floors above what that loses (2^-120), and the separation test
// decides only on normal values; a determinant within a few subnormals of its bound may still be decided differently
// here and on such a device (the lockstep tests would say so), never wrongly.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace cullide {

/// What the filter says of a pair (exact.comp writes Uncertain and Within; Apart pairs are not written).
enum class FilterVerdict : std::uint32_t { Apart = 0, Uncertain = 1, Within = 2 };

namespace filter {

struct V3 {
    float x, y, z;
};

inline V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float maxAbs(V3 a) { return std::max(std::max(std::fabs(a.x), std::fabs(a.y)), std::fabs(a.z)); }
inline float sumAbs(V3 a) { return std::fabs(a.x) + std::fabs(a.y) + std::fabs(a.z); }

/// The bounds one pair is decided with.
struct Bounds {
    float m;      ///< max |component| of the vertices relative to the first one
    float delta;  ///< error of such a component against the true one
    float orientErr;  ///< error of an orientation determinant over differences of them
};

inline Bounds boundsOf(const V3 v[6], const V3 r[6]) {
    float pos = 0.0f;
    float m = 0.0f;
    for (int k = 0; k < 6; ++k) {
        pos = std::max(pos, maxAbs(v[k]));
        m = std::max(m, maxAbs(r[k]));
    }
    Bounds b;
    b.m = m;
    const float e = pos * 0x1p-23f + 0x1p-125f;  // a device coordinate's error
    b.delta = (e + e) + m * 0x1p-23f;            // ... of a difference of two, rounded
    // A determinant of three differences of relative vertices: components below md, each off by at most dd. Its
    // six products of three move by at most (md + dd)^3 - md^3 each; Shewchuk's bound for its evaluation is below
    // 8 u times its permanent (6 md^3).
    const float md = (m + m) * (1.0f + 0x1p-20f);
    const float dd = (b.delta + b.delta) + m * 0x1p-22f;
    const float moved = 6.0f * dd * (3.0f * md * md + 3.0f * md * dd + dd * dd);
    b.orientErr = (moved + 48.0f * 0x1p-24f * md * md * md) * (1.0f + 0x1p-10f) + 0x1p-120f;
    return b;
}

/// Whether axis w separates the triangles (relative vertices r[0..2] and r[3..5]) by more than reach * |w|, their
/// projections' error taken off.
inline bool apartAlong(V3 w, const V3 r[6], const Bounds& b, float reach) {
    const float errP = (sumAbs(w) * (b.delta + b.m * 0x1p-22f) * (1.0f + 0x1p-20f) + 0x1p-120f) * 2.0f;
    const float p0 = dot(r[0], w), p1 = dot(r[1], w), p2 = dot(r[2], w);
    const float q0 = dot(r[3], w), q1 = dot(r[4], w), q2 = dot(r[5], w);
    const float minA = std::min(std::min(p0, p1), p2), maxA = std::max(std::max(p0, p1), p2);
    const float minB = std::min(std::min(q0, q1), q2), maxB = std::max(std::max(q0, q1), q2);
    const float gap = std::max(minB - maxA, minA - maxB);
    const float g = (gap * (1.0f - 0x1p-22f) - errP) * (1.0f - 0x1p-22f);
    // Only normal values decide (a device may flush subnormals to zero): a gap, and the squares compared, of at least
    // 2^-100 (whose squares stay normal).
    if (!(g >= 0x1p-100f)) return false;
    if (reach == 0.0f) return true;
    const float rhs = reach * reach * dot(w, w) * (1.0f + 0x1p-18f);
    if (!(rhs >= 0x1p-100f)) return false;
    return g * g > rhs;
}

/// The certified sign of an orientation determinant d (0: not certain).
inline int signOf(float d, const Bounds& b) { return d > b.orientErr ? 1 : (d < -b.orientErr ? -1 : 0); }

/// orient3d(p, q, s, t) over relative vertices: det[q - p, s - p, t - p].
inline float orient(V3 p, V3 q, V3 s, V3 t) { return dot(cross(sub(q, p), sub(s, p)), sub(t, p)); }

/// Whether edge (p, q), whose ends lie strictly on both sides of the other triangle's plane, certainly passes
/// strictly inside the triangle (s0, s1, s2).
inline bool edgeCrosses(V3 p, V3 q, V3 s0, V3 s1, V3 s2, const Bounds& b) {
    const int o0 = signOf(orient(p, q, s0, s1), b);
    const int o1 = signOf(orient(p, q, s1, s2), b);
    const int o2 = signOf(orient(p, q, s2, s0), b);
    return o0 != 0 && o0 == o1 && o1 == o2;
}

/// Whether some edge of triangle (t0, t1, t2) certainly crosses the inside of triangle (s0, s1, s2).
inline bool crossesInside(V3 t0, V3 t1, V3 t2, V3 s0, V3 s1, V3 s2, const Bounds& b) {
    const V3 n = cross(sub(s1, s0), sub(s2, s0));
    const int c0 = signOf(dot(n, sub(t0, s0)), b);
    const int c1 = signOf(dot(n, sub(t1, s0)), b);
    const int c2 = signOf(dot(n, sub(t2, s0)), b);
    return (c0 * c1 < 0 && edgeCrosses(t0, t1, s0, s1, s2, b)) || (c1 * c2 < 0 && edgeCrosses(t1, t2, s0, s1, s2, b)) ||
           (c2 * c0 < 0 && edgeCrosses(t2, t0, s0, s1, s2, b));
}

}  // namespace filter

/// The verdict on triangles (v[0], v[1], v[2]) and (v[3], v[4], v[5]), device coordinates. `reach`: 0 for margin 0,
/// otherwise the margin plus the CPU distance's error, rounded up (DeviceExact.h, exactReach).
inline FilterVerdict filterTrianglePair(const float (&v)[6][3], float reach) {
    using namespace filter;
    V3 p[6];
    for (int k = 0; k < 6; ++k) p[k] = {v[k][0], v[k][1], v[k][2]};
    V3 r[6];
    for (int k = 0; k < 6; ++k) r[k] = sub(p[k], p[0]);
    const Bounds b = boundsOf(p, r);
    if (!(b.m <= 0x1p36f)) return FilterVerdict::Uncertain;  // NaN, or products that may overflow
    const V3 ea[3] = {r[1], r[2], sub(r[2], r[1])};
    const V3 eb[3] = {sub(r[4], r[3]), sub(r[5], r[3]), sub(r[5], r[4])};
    if (apartAlong(cross(ea[0], ea[1]), r, b, reach) || apartAlong(cross(eb[0], eb[1]), r, b, reach))
        return FilterVerdict::Apart;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (apartAlong(cross(ea[i], eb[j]), r, b, reach)) return FilterVerdict::Apart;
    if (crossesInside(r[0], r[1], r[2], r[3], r[4], r[5], b) || crossesInside(r[3], r[4], r[5], r[0], r[1], r[2], b))
        return FilterVerdict::Within;
    return FilterVerdict::Uncertain;
}

}  // namespace cullide
