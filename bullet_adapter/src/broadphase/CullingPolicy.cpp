#include "broadphase/CullingPolicy.h"

#include <algorithm>

namespace cullide::bullet {

bool trianglesConsumed(GeometryKind a, GeometryKind b, const CulledKinds& kinds) {
    if (a > b) std::swap(a, b);  // enum order: None, GImpactMesh, TriangleMesh, ConvexHull, Compound
    if (a == GeometryKind::GImpactMesh)
        return (kinds.gimpactVsGimpact && b == GeometryKind::GImpactMesh) ||
               (kinds.gimpactVsMesh && b == GeometryKind::TriangleMesh);
    if (a == GeometryKind::TriangleMesh)
        return kinds.convexVsMesh && (b == GeometryKind::ConvexHull || b == GeometryKind::Compound);
    return false;
}

bool prunedByCuller(GeometryKind a, bool convexA, GeometryKind b, bool convexB, const CulledKinds& kinds) {
    if (!kinds.gimpactVsConvex) return false;
    auto convex = [](GeometryKind k, bool isConvex) {
        return k == GeometryKind::ConvexHull || k == GeometryKind::Compound || (k == GeometryKind::None && isConvex);
    };
    return (a == GeometryKind::GImpactMesh && convex(b, convexB)) || (b == GeometryKind::GImpactMesh && convex(a, convexA));
}

double requiredCullingMargin(const std::vector<MarginEntry>& objects, const BreakingRule& rule) {
    double gimpact = -1.0, hull = -1.0, mesh = -1.0;  // largest margin per kind (-1: none in the frame)
    double coordinate = 0.0;
    bool boxes = false;
    double largest = 0.0, second = 0.0, largestMoving = 0.0;  // motion discs
    for (const MarginEntry& o : objects) {
        if (o.motionDisc > largest) {
            second = largest;
            largest = o.motionDisc;
        } else {
            second = std::max(second, o.motionDisc);
        }
        if (o.moving) largestMoving = std::max(largestMoving, o.motionDisc);
        coordinate = std::max(coordinate, o.coordinate);
        switch (o.kind) {
            case GeometryKind::GImpactMesh: gimpact = std::max(gimpact, o.margin); break;
            case GeometryKind::ConvexHull: hull = std::max(hull, o.margin); break;
            case GeometryKind::Compound:
                // Hull children go through the hull rules; other children are boxes that include their margin.
                hull = std::max(hull, o.margin);
                boxes = true;
                break;
            case GeometryKind::TriangleMesh: mesh = std::max(mesh, o.margin); break;
            case GeometryKind::None: boxes = true; break;
        }
    }
    double t = rule.threshold;
    if (rule.relative) t *= std::max(1.0, std::min(second, largestMoving));
    double d = boxes ? 1.5 * t : 0.0;
    // (A Bullet built with BULLET_TRIANGLE_COLLISION uses GJK on GImpact triangle pairs instead, within 2 g + t: not
    // Debian's build; such an application sets Settings::margin to 2 g + t.)
    const double slack = 8.0 * rule.epsilon * coordinate;
    if (gimpact >= 0) d = std::max(d, 2.2 * gimpact + slack);
    if (gimpact >= 0 && boxes) d = std::max(d, gimpact + t);
    if (gimpact >= 0 && hull >= 0) d = std::max(d, gimpact + hull + t);
    if (gimpact >= 0 && mesh >= 0) d = std::max(d, gimpact + mesh + t);
    if (hull >= 0) d = std::max({d, 2 * hull + 1.5 * t, hull + std::max(mesh, 0.0) + 1.5 * t});
    if (mesh >= 0) d = std::max(d, mesh + 1.5 * t);
    return std::max(d, 1e-9);
}

std::optional<double> cullingMarginToMake(double required, double current, double requested, std::uint64_t step,
                                          bool shrinkFailed) {
    if (required <= current) {
        if (current <= requested || shrinkFailed) return std::nullopt;
        const bool muchTooLarge = required < 0.5 * current;
        const bool firstStepTooLarge = step <= 1 && required < current;  // the constructor's default: fit it exactly
        if (!muchTooLarge && !firstStepTooLarge) return std::nullopt;
    }
    return std::max(requested, (step > 1 ? 1.25 : 1.0) * required);
}

}  // namespace cullide::bullet
