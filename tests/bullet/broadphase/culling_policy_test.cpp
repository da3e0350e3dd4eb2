// The broadphase's culling policy as pure functions: which pairs go through the CULLIDE levels, and the margin rule.
#include "broadphase/CullingPolicy.h"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

namespace cullide::test {
namespace {

using bullet::GeometryKind;
using bullet::MarginEntry;

TEST(CullingPolicy, EachPairOfGeometryKindsHasItsSwitch) {
    using K = GeometryKind;
    using bullet::culledKindOf;
    const K all[] = {K::None, K::GImpactMesh, K::TriangleMesh, K::ConvexHull, K::Compound};
    for (K a : all)
        for (K b : all)
            for (int convex = 0; convex < 4; ++convex) {
                const bool ca = (convex & 1) != 0, cb = (convex & 2) != 0;
                const auto is = [&](K x, K y) { return (a == x && b == y) || (a == y && b == x); };
                const auto solid = [](K k, bool c) { return k == K::ConvexHull || k == K::Compound || (k == K::None && c); };
                std::optional<CulledKind> want;
                if (is(K::GImpactMesh, K::GImpactMesh)) want = CulledKind::GImpactPair;
                else if (is(K::GImpactMesh, K::TriangleMesh)) want = CulledKind::GImpactMesh;
                else if ((a == K::GImpactMesh && solid(b, cb)) || (b == K::GImpactMesh && solid(a, ca)))
                    want = CulledKind::GImpactConvex;
                else if (is(K::TriangleMesh, K::ConvexHull) || is(K::TriangleMesh, K::Compound))
                    want = CulledKind::ConvexMesh;
                EXPECT_EQ(culledKindOf(a, ca, b, cb), want) << int(a) << " " << int(b) << " " << convex;
                EXPECT_EQ(culledKindOf(a, ca, b, cb), culledKindOf(b, cb, a, ca));
            }
    // Never: a soft body or a concave shape (None, not convex) against GImpact, primitives, hulls against hulls.
    EXPECT_FALSE(culledKindOf(K::GImpactMesh, false, K::None, false).has_value());
    EXPECT_FALSE(culledKindOf(K::ConvexHull, true, K::ConvexHull, true).has_value());
    EXPECT_FALSE(culledKindOf(K::TriangleMesh, false, K::None, true).has_value());
    bullet::CulledKinds kinds;
    EXPECT_FALSE(kinds.any());
    kinds.set(CulledKind::GImpactConvex, true);
    EXPECT_TRUE(kinds.any());
    EXPECT_TRUE(kinds[CulledKind::GImpactConvex]);
    EXPECT_FALSE(kinds[CulledKind::GImpactPair]);
}

MarginEntry entry(GeometryKind kind, double margin, double disc, double coordinate = 0.0) {
    MarginEntry e;
    e.kind = kind;
    e.margin = margin;
    e.motionDisc = disc;
    e.coordinate = coordinate;
    return e;
}

TEST(CullingPolicy, ReachOfEachKindOfPair) {
    using K = GeometryKind;
    bullet::BreakingRule fixed;
    fixed.relative = false;
    fixed.threshold = 0.02;
    const double eps = fixed.epsilon;
    // GImpact pair: 1.1 (g_a + g_b): the clip method's points above a plane; no threshold.
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::GImpactMesh, 0.05, 1), entry(K::GImpactMesh, 0.03, 1), fixed),
                     1.1 * 0.08);
    // Margin 0: only the float slack at the objects' coordinates (never below 1e-9).
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::GImpactMesh, 0, 1, 3.0), entry(K::GImpactMesh, 0, 1, 2.0), fixed),
                     8.0 * eps * 3.0);
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::GImpactMesh, 0, 1), entry(K::GImpactMesh, 0, 1), fixed), 1e-9);
    // GImpact against a mesh, a hull, a compound, a convex box: g + m + t (GJK, the manifold rebuilt every step).
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::GImpactMesh, 0.01, 1), entry(K::TriangleMesh, 0.04, 50), fixed),
                     0.01 + 0.04 + 0.02);
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::ConvexHull, 0.04, 1), entry(K::GImpactMesh, 0.01, 1), fixed),
                     0.01 + 0.04 + 0.02);
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::None, 0.04, 1), entry(K::GImpactMesh, 0.01, 1), fixed),
                     0.01 + 0.04 + 0.02);
    // Hull or compound against a mesh: a persistent manifold keeps points within 1.5 t.
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::ConvexHull, 0.04, 1), entry(K::TriangleMesh, 0.0, 50), fixed),
                     0.04 + 1.5 * 0.02);
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::TriangleMesh, 0.02, 50), entry(K::Compound, 0.04, 2), fixed),
                     0.06 + 1.5 * 0.02);
}

TEST(CullingPolicy, RelativeThresholdIsThePairsOwn) {
    using K = GeometryKind;
    bullet::BreakingRule relative;
    relative.threshold = 0.02;
    // getNewManifold's threshold: the smaller motion disc of the two, as Bullet computes it (below 1 too).
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::GImpactMesh, 0.01, 3), entry(K::TriangleMesh, 0.04, 50), relative),
                     0.05 + 0.02 * 3);
    EXPECT_DOUBLE_EQ(bullet::pairReach(entry(K::ConvexHull, 0.04, 0.5), entry(K::TriangleMesh, 0.0, 0.5), relative),
                     0.04 + 1.5 * 0.02 * 0.5);
}

TEST(CullingPolicy, TheFrameTakesItsLargestPairReach) {
    using K = GeometryKind;
    bullet::BreakingRule rule;
    const std::vector<MarginEntry> objects{entry(K::GImpactMesh, 0.0, 1), entry(K::GImpactMesh, 0.0, 1),
                                           entry(K::TriangleMesh, 0.04, 40), entry(K::ConvexHull, 0.04, 1)};
    // A pair's reach counts only where the pair is in the frame: two margin-0 GImpact meshes alone need nothing.
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin(objects, {{0, 1}}, rule), 1e-9);
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin(objects, {{0, 1}, {2, 3}}, rule),
                     bullet::pairReach(objects[2], objects[3], rule));
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin(objects, {}, rule), 1e-9);
}

TEST(CullingPolicy, MarginPolicyGrowsAtOnceAndShrinksOnlyWhenMuchTooLarge) {
    using bullet::cullingMarginToMake;
    // Too small: recreated at once, with 25% headroom.
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.2, 0.12, 0.0, 1, false).value(), 0.25);
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.2, 0.12, 0.0, 5, false).value(), 0.25);
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.2, 0.12, 0.0, 5, true).value(), 0.25);  // growing is never skipped
    // The constructor's default margin is fitted on the first step where it exceeds the headroom.
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.08, 0.12, 0.0, 1, false).value(), 0.1);
    EXPECT_FALSE(cullingMarginToMake(0.1, 0.12, 0.0, 1, false).has_value());
    // Later, a margin up to twice what the scene needs is kept (no recreation every step of a changing scene)...
    EXPECT_FALSE(cullingMarginToMake(0.1, 0.12, 0.0, 2, false).has_value());
    EXPECT_FALSE(cullingMarginToMake(0.06, 0.12, 0.0, 2, false).has_value());
    // ... and one more than twice as large shrinks (with headroom), unless shrinking failed before.
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.05, 0.12, 0.0, 2, false).value(), 0.0625);
    EXPECT_FALSE(cullingMarginToMake(0.05, 0.12, 0.0, 2, true).has_value());
    // The application's margin is a floor: kept when large enough, never gone below.
    EXPECT_FALSE(cullingMarginToMake(0.01, 0.5, 0.5, 1, false).has_value());
    EXPECT_FALSE(cullingMarginToMake(0.01, 0.5, 0.5, 9, false).has_value());
    EXPECT_EQ(cullingMarginToMake(0.01, 2.0, 0.5, 9, false), 0.5);
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.8, 0.5, 0.5, 9, false).value(), 1.0);
}

}  // namespace
}  // namespace cullide::test
