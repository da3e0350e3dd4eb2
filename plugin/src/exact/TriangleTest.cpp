// Exact triangle-triangle intersection from exact predicate signs, plus a double-precision distance.
//
// Pipeline of trianglesIntersect: exact box reject; the signs of B's vertices against A's plane and of A's vertices
// against B's plane (filtered orient3d, plane cross products computed once per triangle), rejecting when one triangle
// lies strictly on one side; when all six signs are non-zero, a Guigue-Devillers style interval test with two more
// orient3d (intersectStraddling); every other configuration (a vertex on the other plane, coplanar, degenerate) goes
// through the edge formulation below. In typical use only the first two steps run and no exact arithmetic is needed.
//
// Edge formulation: two closed triangles intersect iff an edge (closed segment) of one meets the other triangle.
//  * Non-coplanar, non-degenerate: the intersection is a segment on the planes' common line whose end points lie on
//    edges of the triangles, so one of those edges meets the other triangle.
//  * Coplanar: either boundaries cross or one triangle contains the other, and then its edges lie in the other.
//  * Degenerate (collinear or repeated vertices): the triangle is the union of its edges.
// Segment vs triangle: orient3d of the segment ends against the triangle's plane; a strict crossing is decided by the
// three orient3d signs of the segment's line against the edges; a touching end point or a coplanar segment is decided
// in 2D after dropping a coordinate for which the projected triangle is exactly non-degenerate (orient2d != 0), so the
// projection is injective on the plane. Collinear triangles fall back to exact segment-segment tests. Every decision
// is a sign of an exact predicate or an exact comparison of input coordinates; nothing is allocated.
#include "cullide/TriangleTest.h"
#include "exact/CandidateTest.h"

#include "exact/ExactPredicates.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace cullide {

namespace {

using exact::orient3d;

constexpr int kNextAxis[3] = {1, 2, 0};
constexpr int kPrevAxis[3] = {2, 0, 1};

/// orient2d of the projections that drop coordinate k. Equals the sign of ((b-a) x (c-a))_k.
inline int orient2dDrop(const Vec3& a, const Vec3& b, const Vec3& c, int k) {
    const int i = kNextAxis[k], j = kPrevAxis[k];
    return exact::orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

/// Exact: a, b, c collinear (including repeated points).
inline bool collinear3(const Vec3& a, const Vec3& b, const Vec3& c) {
    return orient2dDrop(a, b, c, 0) == 0 && orient2dDrop(a, b, c, 1) == 0 && orient2dDrop(a, b, c, 2) == 0;
}

/// p inside the closed axis-aligned box spanned by a and b.
inline bool inBox3(const Vec3& p, const Vec3& a, const Vec3& b) {
    for (int i = 0; i < 3; ++i) {
        if (p[i] < std::min(a[i], b[i]) || p[i] > std::max(a[i], b[i])) return false;
    }
    return true;
}

/// Same in the plane that drops coordinate k.
inline bool inBox2(const Vec3& p, const Vec3& a, const Vec3& b, int k) {
    const int i = kNextAxis[k], j = kPrevAxis[k];
    return p[i] >= std::min(a[i], b[i]) && p[i] <= std::max(a[i], b[i]) && p[j] >= std::min(a[j], b[j]) &&
           p[j] <= std::max(a[j], b[j]);
}

/// Exact: p on the closed segment ab (ab may be a point).
inline bool pointOnSegment3(const Vec3& p, const Vec3& a, const Vec3& b) {
    return inBox3(p, a, b) && collinear3(a, b, p);
}

/// A coordinate to drop so that the projection of triangle abc is non-degenerate (exactly), or -1 when abc is
/// collinear. The floating-point normal only orders the candidates; the decision is the exact orient2d.
int projectionAxis(const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 n = (b - a).cross(c - a).cwiseAbs();
    int order[3] = {0, 1, 2};
    if (n[order[1]] > n[order[0]]) std::swap(order[0], order[1]);
    if (n[order[2]] > n[order[1]]) std::swap(order[1], order[2]);
    if (n[order[1]] > n[order[0]]) std::swap(order[0], order[1]);
    for (int k : order) {
        if (orient2dDrop(a, b, c, k) != 0) return k;
    }
    return -1;
}

/// Exact closed segment-segment test in the projection dropping k. Valid when the projection is injective on a plane
/// containing all four points. Either segment may be a point.
bool segmentsIntersect2(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, int k) {
    const int d1 = orient2dDrop(p, q, r, k);
    const int d2 = orient2dDrop(p, q, s, k);
    if (d1 != 0 && d1 == d2) return false;
    const int d3 = orient2dDrop(r, s, p, k);
    const int d4 = orient2dDrop(r, s, q, k);
    if (d3 != 0 && d3 == d4) return false;
    if (d1 * d2 < 0 && d3 * d4 < 0) return true;
    return (d1 == 0 && inBox2(r, p, q, k)) || (d2 == 0 && inBox2(s, p, q, k)) || (d3 == 0 && inBox2(p, r, s, k)) ||
           (d4 == 0 && inBox2(q, r, s, k));
}

/// Exact closed segment-segment test in 3D; either segment may be a point.
bool segmentsIntersect3(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
    // Cheap exact box reject.
    for (int i = 0; i < 3; ++i) {
        if (std::max(p[i], q[i]) < std::min(r[i], s[i]) || std::max(r[i], s[i]) < std::min(p[i], q[i])) return false;
    }
    if (p == q) return pointOnSegment3(p, r, s);
    if (r == s) return pointOnSegment3(r, p, q);
    if (orient3d(p, q, r, s) != 0) return false;
    // Coplanar: find a point off the line pq to fix the plane.
    const Vec3* off = nullptr;
    if (!collinear3(p, q, r)) {
        off = &r;
    } else if (!collinear3(p, q, s)) {
        off = &s;
    } else {
        // All four collinear: the boxes decide.
        return inBox3(r, p, q) || inBox3(s, p, q) || inBox3(p, r, s) || inBox3(q, r, s);
    }
    const int k = projectionAxis(p, q, *off);
    return k >= 0 && segmentsIntersect2(p, q, r, s, k);  // k < 0 only for non-finite input
}

/// A triangle with lazily computed projection data.
struct Tri {
    const Vec3* v[3];
    int axis = -2;     ///< dropped coordinate (-1: collinear triangle, -2: not computed yet)
    int orient = 0;    ///< sign of the projected triangle's orientation

    Tri(const Vec3& a, const Vec3& b, const Vec3& c) : v{&a, &b, &c} {}
    const Vec3& operator[](int i) const { return *v[i]; }

    void ensureAxis() {
        if (axis != -2) return;
        axis = projectionAxis(*v[0], *v[1], *v[2]);
        if (axis >= 0) orient = orient2dDrop(*v[0], *v[1], *v[2], axis);
    }
};

/// Exact: closed segment pq meets one of the edges of t (for collinear t).
bool segmentMeetsEdges(const Vec3& p, const Vec3& q, const Tri& t) {
    return segmentsIntersect3(p, q, t[0], t[1]) || segmentsIntersect3(p, q, t[1], t[2]) ||
           segmentsIntersect3(p, q, t[2], t[0]);
}

/// Exact: p (in the plane of the non-degenerate triangle t) inside the closed triangle.
bool pointInTriangle2(const Vec3& p, Tri& t) {
    t.ensureAxis();
    // Exact predicates never get here with a collinear t; the guard only keeps non-finite input well-defined.
    if (t.axis < 0) return segmentMeetsEdges(p, p, t);
    const int k = t.axis, o = t.orient;
    if (orient2dDrop(t[0], t[1], p, k) == -o) return false;
    if (orient2dDrop(t[1], t[2], p, k) == -o) return false;
    if (orient2dDrop(t[2], t[0], p, k) == -o) return false;
    return true;
}

/// Exact: closed segment pq meets the closed non-degenerate triangle t. sp, sq = orient3d(t0, t1, t2, p / q).
bool segmentTriangle(const Vec3& p, const Vec3& q, int sp, int sq, Tri& t) {
    if (sp == sq) {
        if (sp != 0) return false;
        // Segment in the triangle's plane.
        t.ensureAxis();
        if (t.axis < 0) return segmentMeetsEdges(p, q, t);  // non-finite input only, see pointInTriangle2
        const int k = t.axis;
        return pointInTriangle2(p, t) || pointInTriangle2(q, t) || segmentsIntersect2(p, q, t[0], t[1], k) ||
               segmentsIntersect2(p, q, t[1], t[2], k) || segmentsIntersect2(p, q, t[2], t[0], k);
    }
    if (sp == 0) return pointInTriangle2(p, t);
    if (sq == 0) return pointInTriangle2(q, t);
    // Strict crossing of the plane at one interior point of pq: the line pq must pass through the closed triangle,
    // i.e. its three orientations against the directed edges must not have opposite signs.
    const int s1 = orient3d(p, q, t[0], t[1]);
    const int s2 = orient3d(p, q, t[1], t[2]);
    if (s1 * s2 < 0) return false;
    const int s3 = orient3d(p, q, t[2], t[0]);
    return !(s1 * s3 < 0 || s2 * s3 < 0);
}

/// Exact: some edge of `e` (vertices e0, e1, e2, signs s[i] against t's plane) meets the non-degenerate triangle t.
bool edgesMeetTriangle(const Vec3& e0, const Vec3& e1, const Vec3& e2, const int s[3], Tri& t) {
    return segmentTriangle(e0, e1, s[0], s[1], t) || segmentTriangle(e1, e2, s[1], s[2], t) ||
           segmentTriangle(e2, e0, s[2], s[0], t);
}

/// Exact: two coplanar non-degenerate triangles meet (each edge pair and each vertex once, in A's projection, which
/// is injective on the common plane).
bool coplanarTriangles(Tri& ta, Tri& tb) {
    ta.ensureAxis();
    tb.ensureAxis();
    const int k = ta.axis;
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            if (segmentsIntersect2(ta[i], ta[(i + 1) % 3], tb[j], tb[(j + 1) % 3], k)) return true;
        }
    }
    // No boundary crossing: they meet iff one contains the other, i.e. iff a vertex of one lies in the other.
    return pointInTriangle2(ta[0], tb) || pointInTriangle2(tb[0], ta);
}

inline bool allSameStrictSign(const int s[3]) { return s[0] != 0 && s[0] == s[1] && s[1] == s[2]; }
inline bool allZero(const int s[3]) { return s[0] == 0 && s[1] == 0 && s[2] == 0; }

/// Exact closed axis-aligned bounding boxes are disjoint.
inline bool boxesDisjoint(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                          const Vec3& b2, double margin) {
    for (int i = 0; i < 3; ++i) {
        const double aMin = std::min({a0[i], a1[i], a2[i]}), aMax = std::max({a0[i], a1[i], a2[i]});
        const double bMin = std::min({b0[i], b1[i], b2[i]}), bMax = std::max({b0[i], b1[i], b2[i]});
        // With margin 0 the comparisons are exact; with margin > 0 a rounded gap > margin implies a true gap > margin.
        if (margin == 0.0) {
            if (aMax < bMin || bMax < aMin) return true;
        } else if (bMin - aMax > margin || aMin - bMax > margin) {
            return true;
        }
    }
    return false;
}

/// Index of the vertex whose (non-zero) sign differs from the two others'.
inline int loneVertex(const int s[3]) {
    if (s[0] == s[1]) return 2;
    return s[0] == s[2] ? 1 : 0;
}

/// Both triangles strictly straddle the other's plane (all six signs non-zero). Each triangle then meets the planes'
/// common line L in a segment, and they intersect iff the two segments overlap. Relabel so that a0 is the vertex of A
/// alone on the positive side of B's plane and b0 the vertex of B alone on the positive side of A's plane (cyclic
/// shifts, then swapping the two other vertices of the *other* triangle, which flips its plane). With d = nA x nB,
/// A's segment on L runs from its point j on a0a2 to its point i on a0a1 and B's from its point k on b0b1 to its point
/// l on b0b2 (positions t along d). With e = a1 - a0, f = b1 - b0: orient3d(a0, a1, b0, b1) = det[e, b0 - a0, f]
/// = -(k - i) . (e x f) = -(t_k - t_i) / |d|^2 * (d . (e x f)), and d . (e x f) = -(nA . f)(nB . e) < 0 because b0
/// is above A and b1 below, a0 above B and a1 below. So its sign is that of t_k - t_i; likewise orient3d(a0, a2, b0,
/// b2) has the sign of t_l - t_j. The closed intervals [t_j, t_i] and [t_k, t_l] overlap iff t_k <= t_i and
/// t_j <= t_l.
bool intersectStraddling(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                         const Vec3& b2, const int sa[3], const int sb[3]) {
    const Vec3* a[3] = {&a0, &a1, &a2};
    const Vec3* b[3] = {&b0, &b1, &b2};
    const int ia = loneVertex(sa), ib = loneVertex(sb);
    const Vec3* p0 = a[ia];
    const Vec3* p1 = a[(ia + 1) % 3];
    const Vec3* p2 = a[(ia + 2) % 3];
    const Vec3* q0 = b[ib];
    const Vec3* q1 = b[(ib + 1) % 3];
    const Vec3* q2 = b[(ib + 2) % 3];
    if (sa[ia] < 0) std::swap(q1, q2);  // flips B's plane: p0 is now on its positive side
    if (sb[ib] < 0) std::swap(p1, p2);  // flips A's plane: q0 is now on its positive side
    if (orient3d(*p0, *p1, *q0, *q1) > 0) return false;
    return orient3d(*p0, *p2, *q0, *q2) >= 0;
}

bool intersectExact(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                    const Vec3& b2) {
    const exact::PlaneSide planeA(a0, a1, a2);
    const int sb[3] = {planeA.side(b0), planeA.side(b1), planeA.side(b2)};
    if (allSameStrictSign(sb)) return false;
    const exact::PlaneSide planeB(b0, b1, b2);
    const int sa[3] = {planeB.side(a0), planeB.side(a1), planeB.side(a2)};
    if (allSameStrictSign(sa)) return false;

    if (sa[0] != 0 && sa[1] != 0 && sa[2] != 0 && sb[0] != 0 && sb[1] != 0 && sb[2] != 0) {
        // Generic case: each triangle strictly straddles the other's plane (so neither is degenerate).
        return intersectStraddling(a0, a1, a2, b0, b1, b2, sa, sb);
    }

    Tri ta(a0, a1, a2), tb(b0, b1, b2);
    // A collinear triangle gives all-zero orientations; only then can it be degenerate.
    bool aDegenerate = false, bDegenerate = false;
    if (allZero(sb)) {
        ta.ensureAxis();
        aDegenerate = ta.axis < 0;
    }
    if (allZero(sa)) {
        tb.ensureAxis();
        bDegenerate = tb.axis < 0;
    }
    if (aDegenerate && bDegenerate) {
        const Vec3* a[3] = {&a0, &a1, &a2};
        const Vec3* b[3] = {&b0, &b1, &b2};
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                if (segmentsIntersect3(*a[i], *a[(i + 1) % 3], *b[j], *b[(j + 1) % 3])) return true;
            }
        }
        return false;
    }
    if (aDegenerate) return edgesMeetTriangle(a0, a1, a2, sa, tb);
    if (bDegenerate) return edgesMeetTriangle(b0, b1, b2, sb, ta);
    if (allZero(sa) && allZero(sb)) return coplanarTriangles(ta, tb);
    return edgesMeetTriangle(a0, a1, a2, sa, tb) || edgesMeetTriangle(b0, b1, b2, sb, ta);
}

// ---- distance (double precision) ----

inline double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

double pointSegmentDistance2(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 ab = b - a, ap = p - a;
    const double t = ap.dot(ab);
    if (t <= 0.0) return ap.squaredNorm();
    const double len2 = ab.squaredNorm();
    if (t >= len2) return (p - b).squaredNorm();
    return (ap - (t / len2) * ab).squaredNorm();
}

/// Candidate for the distance of segments p1q1 and p2q2 at the lines' mutual closest points, clamped onto the
/// segments: a real pair of points, so never below the true distance (up to rounding). Configurations whose minimum
/// involves an end point (including parallel and degenerate segments) are left to the vertex-triangle candidates.
double segmentPairCandidate2(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
    const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = d1.squaredNorm(), e = d2.squaredNorm();
    const double b = d1.dot(d2);
    const double denom = a * e - b * b;
    if (!(a > 0.0 && e > 0.0 && denom > 0.0)) return std::numeric_limits<double>::infinity();
    const double c = d1.dot(r), f = d2.dot(r);
    double s = clamp01((b * f - c * e) / denom);
    double t = (b * s + f) / e;
    if (t < 0.0 || t > 1.0) {
        t = clamp01(t);
        s = clamp01((b * t - c) / a);
    }
    // Relative to p1 - p2 (exact for nearby points), not via absolute coordinates: keeps tiny distances accurate at
    // large offsets.
    return (r + s * d1 - t * d2).squaredNorm();
}

/// A triangle's data for point-triangle distances.
struct TriangleGeometry {
    const Vec3 *a, *b, *c;
    Vec3 ab, bc, ca, n;
    double nn;
    bool useFace;  ///< not numerically degenerate: the face region is used

    TriangleGeometry(const Vec3& a0, const Vec3& a1, const Vec3& a2)
        : a(&a0), b(&a1), c(&a2), ab(a1 - a0), bc(a2 - a1), ca(a0 - a2) {
        n = ab.cross(a2 - a0);
        nn = n.squaredNorm();
        useFace = nn > 0.0 && nn > 1e-24 * ab.squaredNorm() * ca.squaredNorm();
    }

    /// Squared distance from p to the closed triangle.
    double distance2(const Vec3& p) const {
        if (useFace) {
            const Vec3 ap = p - *a;
            if (n.dot(ab.cross(ap)) >= 0.0 && n.dot(bc.cross(p - *b)) >= 0.0 && n.dot(ca.cross(p - *c)) >= 0.0) {
                // Projection inside: the plane distance is the minimum.
                const double h = n.dot(ap);
                return h * h / nn;
            }
        }
        return std::min(std::min(pointSegmentDistance2(p, *a, *b), pointSegmentDistance2(p, *b, *c)),
                        pointSegmentDistance2(p, *c, *a));
    }
};

/// Distance between two closed triangles assumed disjoint: the minimum of the vertex-triangle candidates (which also
/// cover every vertex-edge pair) and the edge-edge interior candidates. Returns early once the squared distance is at
/// most stop2.
double disjointDistance(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                        const Vec3& b2, double stop2 = -1.0) {
    double best = std::numeric_limits<double>::infinity();
    const TriangleGeometry ga(a0, a1, a2), gb(b0, b1, b2);
    for (const Vec3* p : {&a0, &a1, &a2}) {
        best = std::min(best, gb.distance2(*p));
        if (best <= stop2) return std::sqrt(best);
    }
    for (const Vec3* p : {&b0, &b1, &b2}) {
        best = std::min(best, ga.distance2(*p));
        if (best <= stop2) return std::sqrt(best);
    }
    const Vec3* a[3] = {&a0, &a1, &a2};
    const Vec3* b[3] = {&b0, &b1, &b2};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            best = std::min(best, segmentPairCandidate2(*a[i], *a[(i + 1) % 3], *b[j], *b[(j + 1) % 3]));
            if (best <= stop2) return std::sqrt(best);
        }
    }
    return std::sqrt(best);
}

/// Conservative: every point of triangle (b0, b1, b2) is farther than margin from the plane of (a0, a1, a2), on one
/// side. A true answer guarantees distance > margin (up to the rounding accounted for below).
bool separatedByPlane(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                      const Vec3& b2, double margin) {
    const exact::PlaneSide plane(a0, a1, a2);
    const double* n = plane.normal();
    const double* pn = plane.permanent();
    const double nlen = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double plen = std::sqrt(pn[0] * pn[0] + pn[1] * pn[1] + pn[2] * pn[2]);
    constexpr double eps = exact::detail::kEpsilon;
    // Upper bound of the exact normal's length (each component is off by at most 4 eps (1+O(eps)) of its permanent).
    const double nlenUpper = (nlen * (1.0 + 8.0 * eps) + 5.0 * eps * plen) * (1.0 + 8.0 * eps);
    const double need = margin * nlenUpper * (1.0 + 8.0 * eps);
    int side = 0;
    for (const Vec3* p : {&b0, &b1, &b2}) {
        const double wx = (*p)[0] - a0[0], wy = (*p)[1] - a0[1], wz = (*p)[2] - a0[2];
        const double det = wx * n[0] + wy * n[1] + wz * n[2];
        const double perm = std::fabs(wx) * pn[0] + std::fabs(wy) * pn[1] + std::fabs(wz) * pn[2];
        const double slack =
            exact::detail::orient3dErrorBound(perm, std::fabs(wx) + std::fabs(wy) + std::fabs(wz));
        if (slack < 0.0) return false;  // underflow zone: no conservative answer from floating point
        int s = 0;
        if (det - slack > need) {
            s = 1;
        } else if (-det - slack > need) {
            s = -1;
        }
        if (s == 0 || (side != 0 && s != side)) return false;
        side = s;
    }
    return true;
}

}  // namespace

bool trianglesIntersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                        const Vec3& b2) {
    if (boxesDisjoint(a0, a1, a2, b0, b1, b2, 0.0)) return false;
    return intersectExact(a0, a1, a2, b0, b1, b2);
}

double triangleDistance(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                        const Vec3& b2) {
    if (trianglesIntersect(a0, a1, a2, b0, b1, b2)) return 0.0;
    // Disjoint (exactly): never report 0, even when the rounded distance of a near-contact underflows or cancels.
    return std::max(disjointDistance(a0, a1, a2, b0, b1, b2), std::numeric_limits<double>::denorm_min());
}

bool trianglesWithin(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                     const Vec3& b2, double margin) {
    if (boxesDisjoint(a0, a1, a2, b0, b1, b2, margin > 0.0 ? margin : 0.0)) return false;
    return candidateWithin(a0, a1, a2, b0, b1, b2, margin);
}

bool candidateWithin(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                     const Vec3& b2, double margin) {
    if (!(margin > 0.0)) return intersectExact(a0, a1, a2, b0, b1, b2);
    if (separatedByPlane(a0, a1, a2, b0, b1, b2, margin) || separatedByPlane(b0, b1, b2, a0, a1, a2, margin)) {
        return false;
    }
    if (intersectExact(a0, a1, a2, b0, b1, b2)) return true;
    // Early exit below (margin (1 - 4 eps))^2, where the square root is certainly <= margin: the answer is then the
    // same as comparing triangleDistance with the margin.
    const double shrunk = margin * (1.0 - 4.0 * exact::detail::kEpsilon);
    const double stop2 = shrunk * shrunk;
    return disjointDistance(a0, a1, a2, b0, b1, b2, std::isfinite(stop2) ? stop2 : -1.0) <= margin;
}

}  // namespace cullide
