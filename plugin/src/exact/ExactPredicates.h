// Exact geometric predicates on double inputs: a floating-point filter with a rigorous (semi-static) error bound,
// backed by exact expansion arithmetic (Shewchuk-style non-overlapping expansions) when the filter cannot decide.
//
// Conventions
//   orient3d(a,b,c,d) = sign( ((b-a) x (c-a)) . (d-a) )   (+1: d lies on the side the right-hand normal of abc
//                                                            points to; 0: the four points are coplanar)
//   orient2d(a,b,c)   = sign( (b-a) x (c-a) )             (+1: a,b,c counter-clockwise; 0: collinear)
//
// The signs are exact for all finite inputs, subnormal and huge ones included: the filter's bound covers underflow
// (and overflow yields inf/NaN, which never passes the filter); the exact stage uses floating-point expansions when
// every non-zero coordinate has a magnitude in [2^-300, 2^300] (no intermediate product can then overflow or lose bits
// to underflow), and a fixed-size big-integer evaluation otherwise. The code relies on IEEE-754 binary64 arithmetic in
// round-to-nearest-even mode (the default) and must not be compiled with -ffast-math or similar value-changing
// options. Contraction into FMA is harmless (it only removes roundings).
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <cstdint>

namespace cullide::exact {

namespace detail {

/// Unit round-off of binary64 (2^-53).
constexpr double kEpsilon = 0x1p-53;
/// orient3d filter: |computed - exact| <= 8 eps (1 + 64 eps) * permanent (see ExactPredicates.cpp for the derivation).
constexpr double kOrient3dBound = 0x1p-50 + 0x1p-97;
/// orient2d filter: |computed - exact| <= 4 eps (1 + 64 eps) * permanent.
constexpr double kOrient2dBound = 0x1p-51 + 0x1p-98;
/// The filter only decides when its bound exceeds 2^-1000 (|w.x| + |w.y| + |w.z| + 1): then the absolute errors of
/// products that underflow are negligible against the bound's margin. The test stays in the normal range, so typical
/// inputs never pay for subnormal arithmetic.
constexpr double kUnderflowGuard = 0x1p-1000;

/// The orient3d filter's error bound from the computed permanent and |w.x| + |w.y| + |w.z| (w = d - a), or a negative
/// value when the filter must not decide (underflow zone, or NaN).
inline double orient3dErrorBound(double permanent, double absW) {
    const double bound = kOrient3dBound * permanent;
    return bound > kUnderflowGuard * (absW + 1.0) ? bound : -1.0;
}

// Out-of-line exact evaluation used when the filter fails; counts the fallback.
int orient3dFallback(const double* a, const double* b, const double* c, const double* d);
int orient2dFallback(double ax, double ay, double bx, double by, double cx, double cy);

}  // namespace detail

/// Exact sign of the 3x3 determinant [b-a; c-a; d-a], no filter (for tests and benchmarks).
int orient3dExact(const double* a, const double* b, const double* c, const double* d);
/// Exact sign of the 2x2 determinant [b-a; c-a], no filter.
int orient2dExact(double ax, double ay, double bx, double by, double cx, double cy);
/// The big-integer evaluation alone (normally used only outside the expansions' range); for tests.
int orient3dExactBigInt(const double* a, const double* b, const double* c, const double* d);
int orient2dExactBigInt(double ax, double ay, double bx, double by, double cx, double cy);

/// Filtered exact orient3d.
inline int orient3d(const double* a, const double* b, const double* c, const double* d) {
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
    const double uyvz = uy * vz, uzvy = uz * vy;
    const double uzvx = uz * vx, uxvz = ux * vz;
    const double uxvy = ux * vy, uyvx = uy * vx;
    const double det = wx * (uyvz - uzvy) + wy * (uzvx - uxvz) + wz * (uxvy - uyvx);
    const double awx = std::fabs(wx), awy = std::fabs(wy), awz = std::fabs(wz);
    const double perm = awx * (std::fabs(uyvz) + std::fabs(uzvy)) + awy * (std::fabs(uzvx) + std::fabs(uxvz)) +
                        awz * (std::fabs(uxvy) + std::fabs(uyvx));
    const double bound = detail::orient3dErrorBound(perm, awx + awy + awz);
    if (bound >= 0.0) {
        if (det > bound) return 1;
        if (-det > bound) return -1;
    }
    return detail::orient3dFallback(a, b, c, d);
}

inline int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) {
    return orient3d(a.data(), b.data(), c.data(), d.data());
}

/// Filtered exact orient2d on (x, y) pairs.
inline int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const double ux = bx - ax, uy = by - ay;
    const double vx = cx - ax, vy = cy - ay;
    const double l = ux * vy, r = uy * vx;
    const double det = l - r;
    const double bound = detail::kOrient2dBound * (std::fabs(l) + std::fabs(r));
    if (bound > detail::kUnderflowGuard) {
        if (det > bound) return 1;
        if (-det > bound) return -1;
    }
    return detail::orient2dFallback(ax, ay, bx, by, cx, cy);
}

/// orient3d(a, b, c, d) for one plane (a, b, c) and many query points d: the plane's cross products are computed once.
/// side(d) returns exactly orient3d(a, b, c, d) (same arithmetic, same filter).
class PlaneSide {
public:
    PlaneSide(const double* a, const double* b, const double* c) : a_(a), b_(b), c_(c) {
        const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
        const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
        const double uyvz = uy * vz, uzvy = uz * vy;
        const double uzvx = uz * vx, uxvz = ux * vz;
        const double uxvy = ux * vy, uyvx = uy * vx;
        n_[0] = uyvz - uzvy;
        n_[1] = uzvx - uxvz;
        n_[2] = uxvy - uyvx;
        p_[0] = std::fabs(uyvz) + std::fabs(uzvy);
        p_[1] = std::fabs(uzvx) + std::fabs(uxvz);
        p_[2] = std::fabs(uxvy) + std::fabs(uyvx);
    }
    PlaneSide(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
        : PlaneSide(a.data(), b.data(), c.data()) {}

    int side(const double* d) const {
        const double wx = d[0] - a_[0], wy = d[1] - a_[1], wz = d[2] - a_[2];
        const double det = wx * n_[0] + wy * n_[1] + wz * n_[2];
        const double awx = std::fabs(wx), awy = std::fabs(wy), awz = std::fabs(wz);
        const double perm = awx * p_[0] + awy * p_[1] + awz * p_[2];
        const double bound = detail::orient3dErrorBound(perm, awx + awy + awz);
        if (bound >= 0.0) {
            if (det > bound) return 1;
            if (-det > bound) return -1;
        }
        return detail::orient3dFallback(a_, b_, c_, d);
    }
    int side(const Eigen::Vector3d& d) const { return side(d.data()); }

    /// The floating-point normal (b-a) x (c-a) and its component-wise error permanent (|.| terms summed).
    const double* normal() const { return n_; }
    const double* permanent() const { return p_; }

private:
    const double* a_;
    const double* b_;
    const double* c_;
    double n_[3];
    double p_[3];
};

/// Number of predicate evaluations (all threads) that the filter could not decide and that went to exact arithmetic.
std::uint64_t exactFallbackCount() noexcept;
void resetExactFallbackCount() noexcept;

}  // namespace cullide::exact
