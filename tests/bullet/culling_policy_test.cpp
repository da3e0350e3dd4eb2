// The broadphase's culling policy as pure functions: which pairs go through the CULLIDE levels, and the margin rule.
#include "broadphase/CullingPolicy.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide::test {
namespace {

using bullet::GeometryKind;
using bullet::MarginEntry;

TEST(CullingPolicy, OnlyPairsWhoseTrianglesAreReadAreCulled) {
    const GeometryKind all[] = {GeometryKind::None, GeometryKind::GImpactMesh, GeometryKind::TriangleMesh,
                                GeometryKind::ConvexHull, GeometryKind::Compound};
    for (GeometryKind a : all)
        for (GeometryKind b : all)
            for (int bits = 0; bits < 8; ++bits) {
                bullet::CulledKinds kinds;
                kinds.convexVsMesh = (bits & 1) != 0;
                kinds.gimpactVsGimpact = (bits & 2) != 0;
                kinds.gimpactVsMesh = (bits & 4) != 0;
                const auto is = [&](GeometryKind x, GeometryKind y) {
                    return (a == x && b == y) || (a == y && b == x);
                };
                const bool gimpact = (kinds.gimpactVsGimpact && is(GeometryKind::GImpactMesh, GeometryKind::GImpactMesh)) ||
                                     (kinds.gimpactVsMesh && is(GeometryKind::GImpactMesh, GeometryKind::TriangleMesh));
                const bool convexMesh = kinds.convexVsMesh && (is(GeometryKind::ConvexHull, GeometryKind::TriangleMesh) ||
                                                               is(GeometryKind::Compound, GeometryKind::TriangleMesh));
                EXPECT_EQ(bullet::trianglesConsumed(a, b, kinds), gimpact || convexMesh)
                    << int(a) << " " << int(b) << " " << bits;
                EXPECT_EQ(bullet::trianglesConsumed(a, b, kinds), bullet::trianglesConsumed(b, a, kinds));
            }
    EXPECT_FALSE(bullet::CulledKinds{}.any());
    bullet::CulledKinds one;
    one.gimpactVsConvex = true;
    EXPECT_TRUE(one.any());
    // The defaults: no kind of pair is culled for its triangles.
    for (GeometryKind a : all)
        for (GeometryKind b : all) EXPECT_FALSE(bullet::trianglesConsumed(a, b, bullet::CulledKinds{}));
}

TEST(CullingPolicy, GImpactAgainstConvexShapesIsPrunedByTheCullerWhenAsked) {
    using K = GeometryKind;
    bullet::CulledKinds on;
    on.gimpactVsConvex = true;
    EXPECT_TRUE(bullet::prunedByCuller(K::GImpactMesh, false, K::None, true, on));  // a box, a sphere
    EXPECT_TRUE(bullet::prunedByCuller(K::ConvexHull, true, K::GImpactMesh, false, on));
    EXPECT_TRUE(bullet::prunedByCuller(K::GImpactMesh, false, K::Compound, false, on));
    EXPECT_FALSE(bullet::prunedByCuller(K::GImpactMesh, false, K::None, false, on));  // a soft body, a concave shape
    EXPECT_FALSE(bullet::prunedByCuller(K::TriangleMesh, false, K::None, true, on));
    EXPECT_FALSE(bullet::prunedByCuller(K::ConvexHull, true, K::None, true, on));
    EXPECT_FALSE(bullet::prunedByCuller(K::GImpactMesh, false, K::GImpactMesh, false, on));  // reads triangles instead
    // Off (the default): no pair is decided by the culler.
    const bullet::CulledKinds off;
    EXPECT_FALSE(bullet::prunedByCuller(K::GImpactMesh, false, K::None, true, off));
    EXPECT_FALSE(bullet::prunedByCuller(K::ConvexHull, true, K::GImpactMesh, false, off));
    EXPECT_FALSE(bullet::prunedByCuller(K::GImpactMesh, false, K::Compound, false, off));
}

MarginEntry entry(GeometryKind kind, double margin, double disc, bool moving, double coordinate = 0.0) {
    MarginEntry e;
    e.kind = kind;
    e.margin = margin;
    e.motionDisc = disc;
    e.moving = moving;
    e.coordinate = coordinate;
    return e;
}

TEST(CullingPolicy, MarginCoversEachRule) {
    bullet::BreakingRule fixed;
    fixed.relative = false;
    fixed.threshold = 0.02;
    // GImpact pair: 2.2 g.
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin({entry(GeometryKind::GImpactMesh, 0.05, 1, true),
                                                    entry(GeometryKind::GImpactMesh, 0.05, 1, true)},
                                                   fixed),
                     2.2 * 0.05);
    // GImpact against a mesh: g + m + t.
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin({entry(GeometryKind::GImpactMesh, 0.01, 1, true),
                                                    entry(GeometryKind::TriangleMesh, 0.04, 50, false)},
                                                   fixed),
                     0.01 + 0.04 + 0.02);
    // Hull against a mesh: persistent manifold, 1.5 t.
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin({entry(GeometryKind::ConvexHull, 0.04, 1, true),
                                                    entry(GeometryKind::TriangleMesh, 0.0, 50, false)},
                                                   fixed),
                     2 * 0.04 + 1.5 * 0.02);
    // Float slack at large coordinates for GImpact.
    const double far = bullet::requiredCullingMargin({entry(GeometryKind::GImpactMesh, 0.05, 1, true, 1e4),
                                                      entry(GeometryKind::GImpactMesh, 0.05, 1, true, 1e4)},
                                                     fixed);
    EXPECT_DOUBLE_EQ(far, 2.2 * 0.05 + 8.0 * fixed.epsilon * 1e4);
    EXPECT_GE(bullet::requiredCullingMargin({}, fixed), 1e-9);
}

TEST(CullingPolicy, RelativeThresholdUsesTheSmallerDiscOfAPossiblePair) {
    bullet::BreakingRule relative;
    relative.threshold = 0.02;
    // A landscape (disc 50) and a moving GImpact body (disc 3): t = 0.02 * 3, not 0.02 * 50. The mesh rule (m + 1.5 t,
    // persistent manifolds against it) is the largest term.
    const double d = bullet::requiredCullingMargin({entry(GeometryKind::GImpactMesh, 0.01, 3, true),
                                                    entry(GeometryKind::TriangleMesh, 0.04, 50, false),
                                                    entry(GeometryKind::TriangleMesh, 0.04, 40, false)},
                                                   relative);
    EXPECT_DOUBLE_EQ(d, 0.04 + 1.5 * 0.02 * 3);
    // Two static objects that pair with each other (a collision world) are both `moving` entries: their pair's
    // threshold counts (the case that lost a contact when only non-static objects bounded t).
    const double statics = bullet::requiredCullingMargin({entry(GeometryKind::GImpactMesh, 0.01, 1.16, true),
                                                          entry(GeometryKind::TriangleMesh, 0.04, 11, true)},
                                                         relative);
    EXPECT_DOUBLE_EQ(statics, 0.04 + 1.5 * 0.02 * 1.16);
    // Discs below 1 never shrink t below the absolute threshold (conservative).
    EXPECT_DOUBLE_EQ(bullet::requiredCullingMargin({entry(GeometryKind::ConvexHull, 0.04, 0.5, true),
                                                    entry(GeometryKind::TriangleMesh, 0.0, 0.5, false)},
                                                   relative),
                     2 * 0.04 + 1.5 * 0.02);
}

TEST(CullingPolicy, MarginPolicyGrowsAtOnceAndShrinksOnlyWhenMuchTooLarge) {
    using bullet::cullingMarginToMake;
    // Too small: recreated at once, exactly on the first step, with 25% headroom later.
    EXPECT_EQ(cullingMarginToMake(0.2, 0.12, 0.0, 1, false), 0.2);
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.2, 0.12, 0.0, 5, false).value(), 0.25);
    EXPECT_DOUBLE_EQ(cullingMarginToMake(0.2, 0.12, 0.0, 5, true).value(), 0.25);  // growing is never skipped
    // The constructor's default margin is fitted on the first step, also when it is large enough.
    EXPECT_EQ(cullingMarginToMake(0.1, 0.12, 0.0, 1, false), 0.1);
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
