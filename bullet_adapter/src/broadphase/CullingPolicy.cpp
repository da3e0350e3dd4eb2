#include "broadphase/CullingPolicy.h"

#include <algorithm>

namespace cullide::bullet {

std::optional<CulledKind> culledKindOf(GeometryKind a, bool convexA, GeometryKind b, bool convexB) {
    using G = GeometryKind;
    const auto both = [&](G x, G y) { return (a == x && b == y) || (a == y && b == x); };
    const auto hullLike = [](G k) { return k == G::ConvexHull || k == G::Compound; };
    const auto convexSolid = [&](G k, bool convex) { return hullLike(k) || (k == G::None && convex); };
    if (both(G::GImpactMesh, G::GImpactMesh)) return CulledKind::GImpactPair;
    if (both(G::GImpactMesh, G::TriangleMesh)) return CulledKind::GImpactMesh;
    if ((a == G::GImpactMesh && convexSolid(b, convexB)) || (b == G::GImpactMesh && convexSolid(a, convexA)))
        return CulledKind::GImpactConvex;
    if ((a == G::TriangleMesh && hullLike(b)) || (b == G::TriangleMesh && hullLike(a))) return CulledKind::ConvexMesh;
    return std::nullopt;
}

double pairReach(const MarginEntry& a, const MarginEntry& b, const BreakingRule& rule) {
    const MarginEntry& lo = a.kind <= b.kind ? a : b;  // enum order: None, GImpactMesh, TriangleMesh, ConvexHull, Compound
    const MarginEntry& hi = a.kind <= b.kind ? b : a;
    const double t = rule.threshold * (rule.relative ? std::min(a.motionDisc, b.motionDisc) : 1.0);
    const double slack = 8.0 * rule.epsilon * std::max(a.coordinate, b.coordinate);
    double reach = 0.0;
    if (lo.kind == GeometryKind::GImpactMesh && hi.kind == GeometryKind::GImpactMesh)
        reach = 1.1 * (lo.margin + hi.margin);
    else if (lo.kind == GeometryKind::GImpactMesh || hi.kind == GeometryKind::GImpactMesh)
        reach = lo.margin + hi.margin + t;  // against a triangle mesh, a hull, a compound or a convex box
    else
        reach = lo.margin + hi.margin + 1.5 * t;  // persistent manifolds: hulls and compounds against meshes
    return std::max(reach + slack, 1e-9);
}

double requiredCullingMargin(const std::vector<MarginEntry>& objects,
                             const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                             const BreakingRule& rule) {
    double d = 1e-9;
    for (const auto& [a, b] : pairs) d = std::max(d, pairReach(objects[a], objects[b], rule));
    return d;
}

std::optional<double> cullingMarginToMake(double required, double current, double requested, std::uint64_t step,
                                          bool shrinkFailed) {
    if (required <= current) {
        if (current <= requested || shrinkFailed) return std::nullopt;
        const bool muchTooLarge = required < 0.5 * current;
        const bool firstStepTooLarge = step <= 1 && 1.25 * required < current;  // the constructor's default: fitted
        if (!muchTooLarge && !firstStepTooLarge) return std::nullopt;
    }
    return std::max(requested, 1.25 * required);
}

}  // namespace cullide::bullet
