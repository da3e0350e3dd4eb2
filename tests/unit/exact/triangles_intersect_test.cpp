// The exact triangle-triangle intersection test (trianglesIntersect): hand-made adversarial cases with known answers
// (coplanar, touching, one ulp apart, slivers, degenerate and non-finite triangles), each checked in all vertex
// orders of both triangles, with the triangles swapped, and under exact similarity transforms.
#include "TriangleCases.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace {

using cullide::triangleDistance;
using cullide::trianglesIntersect;
using cullide::trianglesWithin;
using cullide::Vec3;
using namespace cullide::test;

/// Checks trianglesIntersect == expected in all 6 x 6 vertex orders and both triangle orders (72 calls), and that the
/// distance agrees (0 iff intersecting, the same in every order).
void expectIntersect(const Tri& a, const Tri& b, bool expected, const std::string& what) {
    SCOPED_TRACE(what + ": A = " + str(a) + " B = " + str(b));
    const double d0 = triangleDistance(a[0], a[1], a[2], b[0], b[1], b[2]);
    if (expected) {
        EXPECT_EQ(d0, 0.0);
    } else {
        EXPECT_GT(d0, 0.0);
    }
    int wrong = 0;
    for (const auto& pa : kPerms) {
        for (const auto& pb : kPerms) {
            const Vec3 &a0 = a[pa[0]], &a1 = a[pa[1]], &a2 = a[pa[2]];
            const Vec3 &b0 = b[pb[0]], &b1 = b[pb[1]], &b2 = b[pb[2]];
            wrong += trianglesIntersect(a0, a1, a2, b0, b1, b2) != expected;
            wrong += trianglesIntersect(b0, b1, b2, a0, a1, a2) != expected;
            // margin <= 0 is the exact test too.
            wrong += trianglesWithin(a0, a1, a2, b0, b1, b2, 0.0) != expected;
            wrong += trianglesWithin(b0, b1, b2, a0, a1, a2, -1.0) != expected;
            const double d = triangleDistance(b0, b1, b2, a0, a1, a2);
            EXPECT_NEAR(d, d0, 1e-12 * std::max(1.0, d0));
        }
    }
    EXPECT_EQ(wrong, 0) << "expected " << (expected ? "intersecting" : "disjoint");
}

/// An exact similarity transform (power-of-two scale, then offset) of integer/dyadic cases.
struct Transform {
    double scale;
    Vec3 offset;
    const char* name;
};

const Transform kTransforms[] = {
    {1.0, Vec3::Zero(), "identity"},
    {1.0, Vec3(1e5, -3e5, 7e5), "offset 1e5"},
    {1.0, Vec3(1e6, 1e6, -2e6), "offset 1e6"},
    {1.0, Vec3(1e7, -1e7, 1e7), "offset 1e7"},
    {0x1p-30, Vec3::Zero(), "tiny 1e-9"},
    {0x1p-30, Vec3(1e5, 2e5, -1e5), "tiny 1e-9 at offset 1e5"},
    {0x1p-28, Vec3(-1e7, 1e7, 3e6), "tiny 4e-9 at offset 1e7"},
    {0x1p+40, Vec3::Zero(), "huge 1e12"},
};

Tri apply(const Transform& t, const Tri& tri, bool* exact) {
    Tri out;
    for (int i = 0; i < 3; ++i) {
        out[i] = tri[i] * t.scale + t.offset;
        if (((out[i] - t.offset) / t.scale) != tri[i]) *exact = false;
    }
    return out;
}

/// Runs a case given in small dyadic coordinates under every exact transform.
void expectIntersectAllTransforms(const Tri& a, const Tri& b, bool expected, const std::string& what) {
    for (const Transform& t : kTransforms) {
        bool exact = true;
        const Tri ta = apply(t, a, &exact), tb = apply(t, b, &exact);
        ASSERT_TRUE(exact) << what << " is not exactly representable under " << t.name;
        expectIntersect(ta, tb, expected, what + " [" + t.name + "]");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Coplanar

TEST(TrianglesIntersect, CoplanarOverlapAndContainment) {
    expectIntersectAllTransforms(kA, {V(1, 1, 0), V(5, 1, 0), V(1, 5, 0)}, true, "coplanar overlap");
    expectIntersectAllTransforms(kA, {V(1, 1, 0), V(2, 1, 0), V(1, 2, 0)}, true, "coplanar contained");
    expectIntersectAllTransforms(kA, {V(-1, -1, 0), V(9, -1, 0), V(-1, 9, 0)}, true, "coplanar containing");
    expectIntersectAllTransforms(kA, kA, true, "identical");
    // Star of David: every vertex outside the other, edges cross.
    expectIntersectAllTransforms({V(0, 0, 0), V(6, 0, 0), V(3, 6, 0)}, {V(0, 4, 0), V(6, 4, 0), V(3, -2, 0)}, true,
                                 "coplanar star");
}

TEST(TrianglesIntersect, CoplanarTouching) {
    expectIntersectAllTransforms(kA, {V(4, 0, 0), V(6, 1, 0), V(6, -1, 0)}, true, "coplanar vertex-vertex");
    expectIntersectAllTransforms(kA, {V(2, 2, 0), V(4, 4, 0), V(5, 2, 0)}, true, "coplanar vertex on edge");
    expectIntersectAllTransforms(kA, {V(1, 0, 0), V(3, 0, 0), V(2, -2, 0)}, true, "coplanar edge overlap");
    expectIntersectAllTransforms(kA, {V(4, 0, 0), V(8, 0, 0), V(6, -2, 0)}, true, "coplanar collinear edges touching");
    expectIntersectAllTransforms(kA, {V(5, 0, 0), V(8, 0, 0), V(3, -2, 0)}, false, "coplanar collinear edges gap");
    expectIntersectAllTransforms(kA, {V(0, 0, 0), V(-4, 0, 0), V(0, -4, 0)}, true, "coplanar shared vertex, opposite");
    expectIntersectAllTransforms(kA, {V(0, 0, 0), V(4, 0, 0), V(0, -4, 0)}, true, "coplanar shared edge (hinge)");
    expectIntersectAllTransforms(kA, {V(3, 3, 0), V(5, 5, 0), V(6, 2, 0)}, false, "coplanar near hypotenuse");
}

TEST(TrianglesIntersect, CoplanarDisjointByOneUlp) {
    // B's vertex one ulp beyond the hypotenuse x + y = 4 (and exactly on it as the control).
    for (const Vec3& o : {V(0, 0, 0), V(1e5, 1e5, 0), V(1e6, -1e6, 3), V(1e7, 1e7, -1e7)}) {
        const Tri a = {o + V(0, 0, 0), o + V(4, 0, 0), o + V(0, 4, 0)};
        const double x = o.x() + 2, y = o.y() + 2;
        const Tri touching = {V(x, y, o.z()), o + V(4, 4, 0), o + V(5, 2, 0)};
        const Tri apart = {V(x, up(y), o.z()), o + V(4, 4, 0), o + V(5, 2, 0)};
        const Tri apartX = {V(up(x), y, o.z()), o + V(4, 4, 0), o + V(5, 2, 0)};
        expectIntersect(a, touching, true, "coplanar touching");
        expectIntersect(a, apart, false, "coplanar disjoint by 1 ulp in y");
        expectIntersect(a, apartX, false, "coplanar disjoint by 1 ulp in x");
        // Collinear edges one ulp apart along the line.
        const Tri b = {V(up(o.x() + 4), o.y(), o.z()), o + V(8, 0, 0), o + V(3, -2, 0)};
        expectIntersect(a, b, false, "coplanar collinear edges 1 ulp gap");
    }
}

// ---------------------------------------------------------------------------------------------------------------
// General position and contact

TEST(TrianglesIntersect, PiercingAndSeparated) {
    expectIntersectAllTransforms(kA, {V(1, 1, -1), V(1, 1, 1), V(3, 3, 1)}, true, "edge pierces face");
    expectIntersectAllTransforms(kA, {V(1, 1, 1), V(2, 1, 1), V(1, 2, 1)}, false, "parallel above");
    expectIntersectAllTransforms(kA, {V(5, 5, -1), V(5, 5, 1), V(6, 6, 0)}, false, "crosses plane outside");
    // Edges piercing A's plane on the line of one of A's edges: outside, at a vertex, on the edge.
    // (In both "outside" cases the boxes overlap and B's plane cuts A, so neither early reject applies.)
    expectIntersectAllTransforms(kA, {V(6, 0, -1), V(6, 0, 1), V(3, 0.5, 5)}, false, "pierces on an edge's extension");
    expectIntersectAllTransforms(kA, {V(-5, 8, -1), V(1, 4, 1), V(-5, 11, 0)}, false, "pierces on hypotenuse line");
    expectIntersectAllTransforms(kA, {V(4, 0, -1), V(4, 0, 1), V(7, 3, 0)}, true, "pierces at a vertex");
    expectIntersectAllTransforms(kA, {V(2, 0, -1), V(2, 0, 1), V(7, -3, 0)}, true, "pierces on an edge");
    expectIntersectAllTransforms(kA, {V(3, 3, -1), V(3, 3, 1), V(8, -2, 0)}, false, "B's plane misses A");
    // Each triangle straddles the other's plane, but their intervals on the planes' common line are disjoint.
    expectIntersectAllTransforms(kA, {V(5, 1, -1), V(5, 1, 1), V(3, 1, 5)}, false, "line intervals disjoint");
    expectIntersectAllTransforms(kA, {V(3, 1, -1), V(3, 1, 1), V(9, 1, 0)}, true, "line intervals touch at a point");
    expectIntersectAllTransforms(kA, {V(2, 2, -1), V(2, 2, 1), V(8, -4, 0)}, true, "B's plane holds the hypotenuse");
}

TEST(TrianglesIntersect, EdgeEdge) {
    // B in the plane x = 1; its edge x = 1, y = 0 passes through A's edge y = 0 at (1, 0, 0).
    const Tri b = {V(1, 0, -1), V(1, 0, 1), V(1, -5, 0)};
    expectIntersectAllTransforms(kA, b, true, "edge-edge touching");
    const Tri bAway = {V(1, -0.5, -1), V(1, -0.5, 1), V(1, -5, 0)};
    expectIntersectAllTransforms(kA, bAway, false, "edge-edge skew");
    // Near misses whose boxes overlap (so that the exact stage decides): B in the plane x = 1, its edge crossing z = 0
    // at y = y0 (exactly, at the edge's midpoint), A's cross-section there is y in [0, 3].
    for (const double y0 : {0.0, -0x1p-52, -0.5}) {
        const Tri crossing = {V(1, -1 + y0, -1), V(1, 1 + y0, 1), V(1, -3, 1)};
        expectIntersect(kA, crossing, y0 == 0.0, "edge crossing z = 0 at y = " + std::to_string(y0));
    }
    // Crossing edges that are not axis-aligned.
    expectIntersectAllTransforms(kA, {V(1, 3, -2), V(3, 1, 2), V(9, 9, 0)}, true, "edge through hypotenuse midpoint");
    // Same contact with every vertex strictly off the other triangle's plane (the generic straddling path): the two
    // segments on the planes' common line touch at one end.
    expectIntersectAllTransforms(kA, {V(1, 3, -2), V(3, 1, 2), V(9, 9, 1)}, true, "generic edge-edge contact");
    expectIntersectAllTransforms(kA, {V(1, 3, -2), V(3, 1, 2), V(-5, -5, 1)}, true, "generic edge-edge, overlap");
    expectIntersect(kA, {V(1, up(3.0), -2), V(3, up(1.0), 2), V(9, 9, 1)}, false, "generic edge-edge, 1 ulp apart");
    expectIntersect(kA, {V(1, down(3.0), -2), V(3, down(1.0), 2), V(9, 9, 1)}, true, "generic edge-edge, 1 ulp in");
    // One ulp off: move B by one ulp of 1 in -y (the exact contact disappears).
    const Tri bUlp = {V(1, -0x1p-52, -1), V(1, -0x1p-52, 1), V(1, -5, 0)};
    expectIntersect(kA, bUlp, false, "edge-edge apart by 2^-52");
}

TEST(TrianglesIntersect, VertexOnFace) {
    expectIntersectAllTransforms(kA, {V(1, 1, 0), V(1, 1, 5), V(2, 3, 4)}, true, "vertex on face");
    expectIntersectAllTransforms(kA, {V(2, 2, 0), V(2, 2, 5), V(3, 4, 4)}, true, "vertex on edge");
    expectIntersectAllTransforms(kA, {V(4, 0, 0), V(5, 1, 5), V(3, 4, 4)}, true, "vertex on vertex");
    expectIntersect(kA, {V(1, 1, 0x1p-60), V(1, 1, 5), V(2, 3, 4)}, false, "vertex 2^-60 above face");
    // Same vertex, but B dips below z = 0 outside A (boxes overlap).
    expectIntersect(kA, {V(1, 1, 0x1p-60), V(6, 1, -0x1p-62), V(1, 1, 5)}, false, "vertex 2^-60 above, B dips outside");
    expectIntersect(kA, {V(1, 1, 0), V(6, 1, -0x1p-62), V(1, 1, 5)}, true, "vertex on face, B dips outside");
    expectIntersect(kA, {V(1, 1, -0x1p-60), V(1, 1, 5), V(2, 3, 4)}, true, "vertex 2^-60 below face");
    expectIntersect(kA, {V(up(2.0), 2, 0), V(1, 1, -5), V(1, 1, 5)}, true, "vertex 1 ulp outside, B crosses A");
    expectIntersect(kA, {V(up(2.0), 2, 0), V(up(2.0), 2, 5), V(3, 4, 4)}, false, "vertex 1 ulp beyond edge");
}

TEST(TrianglesIntersect, SharedVertexAndEdge) {
    expectIntersectAllTransforms({V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)}, {V(0, 0, 0), V(-1, 0, 1), V(0, -1, 1)}, true,
                                 "shared vertex");
    expectIntersectAllTransforms({V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)}, {V(0, 0, 0), V(1, 0, 0), V(0, -1, 1)}, true,
                                 "shared edge");
    expectIntersectAllTransforms({V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)}, {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0)}, true,
                                 "shared edge coplanar overlapping");
    // Mesh neighbours sharing a vertex with random-looking coordinates.
    const Vec3 s(0.1234567, -7.654321, 3.14159);
    expectIntersect({s, V(1.1, 0.3, 0.2), V(0.3, 1.7, -0.4)}, {s, V(-1.2, 0.1, 0.9), V(0.2, -1.3, -0.8)}, true,
                    "shared vertex (float)");
}

TEST(TrianglesIntersect, Slivers) {
    // Aspect ratio 1e6: A is a needle along x of height 1e-6 at x = 0.5.
    const double h = 1e-6;
    const Tri sliver = {V(0, 0, 0), V(1, 0, 0), V(0.5, h, 0)};
    expectIntersect(sliver, {V(0.5, h / 2, -1), V(0.5, h / 2, 1), V(0.5, 5, 0)}, true, "plane x=0.5 cuts sliver");
    expectIntersect(sliver, {V(0.5, h, -1), V(0.5, h, 1), V(0.5, 5, 0)}, true, "touches sliver apex");
    expectIntersect(sliver, {V(0.5, up(h), -1), V(0.5, up(h), 1), V(0.5, 5, 0)}, false, "1 ulp above sliver apex");
    expectIntersect(sliver, {V(0.5, up(h), 0), V(0.5, -1, 1), V(0.5, 5, 1)}, false, "vertex 1 ulp above apex");
    expectIntersect(sliver, {V(0.5, h, 0), V(0.5, -1, 1), V(0.5, 5, 1)}, true, "vertex on apex");
    // Two crossing needles in different planes.
    const Tri needle2 = {V(0.5, -1, -h), V(0.5, 1, -h), V(0.5, 0, h)};
    expectIntersect(sliver, needle2, true, "crossing needles");
    const Tri needle3 = {V(0.5, -1, h), V(0.5, 1, h), V(0.5, 0, 2 * h)};
    expectIntersect(sliver, needle3, false, "needles apart");
    const Tri needle4 = {V(0.5, 2 * h, 0), V(0.5, -1, 1), V(0.5, -1, 1 + 2 * h)};
    expectIntersect(sliver, needle4, false, "needle tip just beside the sliver");
    const Tri needle5 = {V(0.5, h / 2, 0), V(0.5, -1, 1), V(0.5, -1, 1 + 2 * h)};
    expectIntersect(sliver, needle5, true, "needle tip on the sliver");
    // Coplanar slivers crossing in a thin overlap.
    expectIntersect(sliver, {V(0.25, -h, 0), V(0.75, 3 * h, 0), V(0.8, 3 * h, 0)}, true, "coplanar slivers crossing");
    expectIntersect(sliver, {V(0, h, 0), V(0.2, h, 0), V(0.1, 2 * h, 0)}, false, "coplanar slivers apart");
}

TEST(TrianglesIntersect, NearlyParallelClosePlanes) {
    // A in z = 1, B one ulp above with identical footprint, then touching at one vertex.
    const Tri a = {V(0, 0, 1), V(4, 0, 1), V(0, 4, 1)};
    const double z1 = up(1.0);
    expectIntersect(a, {V(0, 0, z1), V(4, 0, z1), V(0, 4, z1)}, false, "parallel, 1 ulp apart");
    expectIntersect(a, {V(1, 1, 1), V(4, 0, z1), V(0, 4, z1)}, true, "nearly parallel, touching at a vertex");
    expectIntersect(a, {V(1, 1, down(1.0)), V(4, 0, z1), V(0, 4, z1)}, true, "nearly parallel, crossing");
    // Tilted by 1e-12 across the footprint: crosses z = 1 at x = 1.
    expectIntersect(a, {V(0, 0, 1 - 1e-12), V(4, 0, 1 + 3e-12), V(0, 4, 1 - 1e-12)}, true, "tilted 1e-12 crossing");
    expectIntersect(a, {V(0, 0, 1 + 1e-12), V(4, 0, 1 + 3e-12), V(0, 4, 1 + 1e-12)}, false, "tilted 1e-12 above");
    expectIntersect(a, {V(0, 0, 1 + 1e-12), V(4, 0, 1 + 1e-12), V(0, -4, 1 - 1e-12)}, false, "tilted, crossing outside");
    // Large offset: planes z = 1e7 and z = 1e7 + ulp.
    const double Z = 1e7;
    const Tri big = {V(Z, Z, Z), V(Z + 4, Z, Z), V(Z, Z + 4, Z)};
    expectIntersect(big, {V(Z + 1, Z + 1, up(Z)), V(Z + 3, Z, up(Z)), V(Z, Z + 3, up(Z))}, false, "1e7, 1 ulp apart");
    expectIntersect(big, {V(Z + 1, Z + 1, Z), V(Z + 3, Z, up(Z)), V(Z, Z + 3, up(Z))}, true, "1e7, touching");
    expectIntersect(big, {V(Z + 1, Z + 1, up(Z)), V(Z + 3, Z, up(Z)), V(Z - 3, Z - 3, down(Z))}, false,
                    "1e7, 1 ulp above, crossing outside");
    expectIntersect(big, {V(Z + 1, Z + 1, Z), V(Z + 3, Z, up(Z)), V(Z - 3, Z - 3, down(Z))}, true,
                    "1e7, touching, crossing outside");
}

// ---------------------------------------------------------------------------------------------------------------
// Degenerate triangles

TEST(TrianglesIntersect, PointTriangles) {
    const Vec3 inside(1, 1, 0), onEdge(2, 2, 0), atVertex(4, 0, 0), outside(3, 3, 0), above(1, 1, 1);
    expectIntersectAllTransforms(kA, {inside, inside, inside}, true, "point inside");
    expectIntersectAllTransforms(kA, {onEdge, onEdge, onEdge}, true, "point on edge");
    expectIntersectAllTransforms(kA, {atVertex, atVertex, atVertex}, true, "point at vertex");
    expectIntersectAllTransforms(kA, {outside, outside, outside}, false, "point outside, coplanar");
    expectIntersectAllTransforms(kA, {above, above, above}, false, "point above");
    const Vec3 tinyAbove(1, 1, 0x1p-300);
    expectIntersect(kA, {tinyAbove, tinyAbove, tinyAbove}, false, "point 2^-300 above");
    const double t = std::numeric_limits<double>::denorm_min();
    expectIntersect(kA, {V(1, 1, t), V(1, 1, t), V(1, 1, t)}, false, "point 2^-1074 above");
    expectIntersect(kA, {V(1, 1, t), V(1, 1, -t), V(1, 1, t)}, true, "segment through face, subnormal");
    expectIntersect(kA, {V(2, up(2.0), t), V(2, 2 - 0x1p-51, -t), V(2, 2 - 0x1p-51, -t)}, true,
                    "subnormal segment through the edge");
    expectIntersect(kA, {V(up(2.0), 2, t), V(up(2.0), 2, -t), V(2, 2, t)}, false, "subnormal segment beside edge");
    const Vec3 p(1, 2, 3), q(1, 2, up(3.0));
    expectIntersectAllTransforms({p, p, p}, {p, p, p}, true, "point = point");
    expectIntersect({p, p, p}, {q, q, q}, false, "point vs point 1 ulp apart");
}

TEST(TrianglesIntersect, SegmentTriangles) {
    // Collinear triangles (third vertex between the others) and repeated vertices.
    expectIntersectAllTransforms(kA, {V(1, 1, -1), V(1, 1, 0), V(1, 1, 1)}, true, "segment pierces face");
    expectIntersectAllTransforms(kA, {V(1, 1, 1), V(1, 1, 2), V(1, 1, 3)}, false, "segment above face");
    expectIntersectAllTransforms(kA, {V(1, 1, 0), V(1, 1, 1), V(1, 1, 2)}, true, "segment end on face");
    expectIntersectAllTransforms(kA, {V(-1, 1, 0), V(1, 1, 0), V(5, 1, 0)}, true, "coplanar segment crossing");
    expectIntersectAllTransforms(kA, {V(-1, 5, 0), V(2, 5, 0), V(5, 5, 0)}, false, "coplanar segment outside");
    expectIntersectAllTransforms(kA, {V(-1, 6, 0), V(2.5, 2.5, 0), V(6, -1, 0)}, false, "coplanar segment beside");
    expectIntersectAllTransforms(kA, {V(-1, 5, 0), V(2, 2, 0), V(5, -1, 0)}, true, "coplanar segment on hypotenuse");
    expectIntersectAllTransforms(kA, {V(4, 0, 0), V(6, 0, 0), V(5, 0, 0)}, true, "collinear segment touching vertex");
    expectIntersectAllTransforms(kA, {V(4, 4, 0), V(2, 2, 0), V(2, 2, 0)}, true, "repeated vertex touching edge");
    expectIntersectAllTransforms(kA, {V(4, 4, 0), V(3, 3, 0), V(3, 3, 0)}, false, "repeated vertex off edge");
    expectIntersectAllTransforms(kA, {V(0, 0, -1), V(0, 0, 1), V(0, 0, 1)}, true, "segment through vertex");
    expectIntersect(kA, {V(up(4.0), 0, 0), V(6, 0, 0), V(5, 0, 0)}, false, "collinear segment 1 ulp from vertex");
    expectIntersect(kA, {V(up(4.0), 0, 0), V(3, -1, 0), V(3, -1, 0)}, false, "segment 1 ulp from vertex");
    expectIntersect(kA, {V(4.0, 0, 0), V(3, -1, 0), V(3, -1, 0)}, true, "segment touching vertex");
}

TEST(TrianglesIntersect, DegenerateVersusDegenerate) {
    const Tri seg = {V(-1, 0, 0), V(1, 0, 0), V(0, 0, 0)};
    expectIntersectAllTransforms(seg, {V(0, -1, 0), V(0, 1, 0), V(0, 1, 0)}, true, "segments crossing");
    expectIntersectAllTransforms(seg, {V(0, -1, 1), V(0, 1, 1), V(0, 0, 1)}, false, "segments skew");
    expectIntersectAllTransforms(seg, {V(0, -1, -0.5), V(0, 1, 1.5), V(0, 0, 0.5)}, false, "skew, boxes overlap");
    expectIntersectAllTransforms(seg, {V(0, -1, -1), V(0, 1, 1), V(0, 0, 0)}, true, "crossing, tilted");
    expectIntersectAllTransforms(seg, {V(3, 3, 0), V(-1, -1, 0), V(-1, -1, 0)}, true, "coplanar crossing at the end");
    expectIntersectAllTransforms(seg, {V(3, 3, 0), V(-0.5, -0.5, 0), V(1, 1, 0)}, true, "coplanar crossing at 0");
    expectIntersectAllTransforms(seg, {V(0.5, 2, 0), V(2, -1, 0), V(2, -1, 0)}, false, "coplanar, boxes overlap");
    expectIntersectAllTransforms(seg, {V(1, 0, 0), V(3, 0, 0), V(2, 0, 0)}, true, "collinear segments touching");
    expectIntersectAllTransforms(seg, {V(0.5, 0, 0), V(3, 0, 0), V(2, 0, 0)}, true, "collinear segments overlapping");
    expectIntersectAllTransforms(seg, {V(2, 0, 0), V(3, 0, 0), V(2.5, 0, 0)}, false, "collinear segments gap");
    expectIntersectAllTransforms(seg, {V(-3, 0, 0), V(3, 0, 0), V(2, 0, 0)}, true, "collinear segment containment");
    // A point inside the box of a diagonal segment but off it (the cross product has a single non-zero component).
    const Tri diag = {V(0, 0, 0), V(0, 2, 2), V(0, 1, 1)};
    expectIntersectAllTransforms(diag, {V(0, 1, 0.5), V(0, 1, 0.5), V(0, 1, 0.5)}, false, "point beside diagonal");
    expectIntersectAllTransforms(diag, {V(0, 1, 1), V(0, 1, 1), V(0, 1, 1)}, true, "point on diagonal");
    expectIntersectAllTransforms(diag, {V(0, 1, 0.5), V(0, 3, 2.5), V(0, 3, 2.5)}, false, "parallel diagonals");
    expectIntersectAllTransforms(diag, {V(1, 1, 0.5), V(0, 1, 0.5), V(0, 1, 0.5)}, false, "segment beside diagonal");
    expectIntersectAllTransforms(seg, {V(0, 0, 0), V(0, 1, 0), V(0, 2, 0)}, true, "T junction");
    expectIntersectAllTransforms(seg, {V(0, 1, 0), V(0, 2, 0), V(0, 3, 0)}, false, "T junction gap");
    expectIntersectAllTransforms(seg, {V(0.5, 0, 0), V(0.5, 0, 0), V(0.5, 0, 0)}, true, "point on segment");
    expectIntersectAllTransforms(seg, {V(0.5, 0.5, 0), V(0.5, 0.5, 0), V(0.5, 0.5, 0)}, false, "point off segment");
    expectIntersectAllTransforms(seg, {V(1, 0, 0), V(1, 0, 0), V(1, 0, 0)}, true, "point at segment end");
    // Coplanar but not collinear segments, in a tilted plane.
    expectIntersectAllTransforms({V(0, 0, 0), V(2, 2, 2), V(1, 1, 1)}, {V(0, 2, 2), V(2, 0, 0), V(2, 0, 0)}, true,
                                 "tilted crossing segments");
    expectIntersectAllTransforms({V(0, 0, 0), V(2, 2, 2), V(1, 1, 1)}, {V(0, 2, 2), V(1, 2, 2), V(1, 2, 2)}, false,
                                 "tilted coplanar segments apart");
    // Segments one ulp apart (skew).
    expectIntersect(seg, {V(0, -1, 0x1p-300), V(0, 1, 0x1p-300), V(0, 0, 0x1p-300)}, false, "segments 2^-300 apart");
    expectIntersect(seg, {V(0.5, -1, -0x1p-300), V(0.5, 1, 0x1p-300), V(0.5, 0, 0)}, true, "segments crossing, tilted");
}

TEST(TrianglesIntersect, NonFiniteInputIsWellDefined) {
    // Outside the contract (inputs must be finite), but must not crash or read out of bounds; no answer is asserted.
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    int count = 0;
    for (const double bad : {nan, inf, -inf}) {
        for (int i = 0; i < 9; ++i) {
            Tri b = {V(1, 1, -1), V(1, 1, 1), V(3, 3, 1)};
            b[i / 3][i % 3] = bad;
            count += trianglesIntersect(kA[0], kA[1], kA[2], b[0], b[1], b[2]);
            count += trianglesWithin(b[0], b[1], b[2], kA[0], kA[1], kA[2], 0.5);
            count += std::isnan(triangleDistance(kA[0], kA[1], kA[2], b[0], b[1], b[2]));
        }
    }
    EXPECT_GE(count, 0);
}

}  // namespace
