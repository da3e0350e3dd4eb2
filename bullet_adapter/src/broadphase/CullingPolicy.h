// What the broadphase hands to the culler, as pure functions of the shapes: which object pairs go through the
// CULLIDE levels, and the distance margin d those pairs need. Unit-tested without Bullet worlds (tests/unit).
#pragma once

#include "broadphase/ShapeGeometry.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace cullide::bullet {

/// The kinds of pair whose narrow phase reads the culler's triangles, each an application's setting
/// (CullideBroadphase::setConvexMeshCulling, setGImpactPairCulling, setGImpactMeshCulling; all off by default).
struct CulledKinds {
    bool convexVsMesh = false;      ///< convex hulls and compounds against a triangle mesh
    bool gimpactVsGimpact = false;  ///< GImpact against GImpact
    bool gimpactVsMesh = false;     ///< GImpact against a triangle mesh
    bool gimpactVsConvex = false;   ///< GImpact against a convex shape: decided by the culler (prunedByCuller)

    /// Whether any kind is culled: with none (the default) no pair goes through the culler.
    bool any() const { return convexVsMesh || gimpactVsGimpact || gimpactVsMesh || gimpactVsConvex; }
};

/// Whether the pair's narrow phase reads the culler's surviving triangles (CullideCollisionDispatcher), so that the
/// CULLIDE levels run for it: the pairs of the kinds set in `kinds`. Every other pair (primitives, hull-hull,
/// hull-GImpact, by default GImpact-GImpact and GImpact-mesh, ...) goes from the object level straight to the
/// dispatcher's algorithms: nobody would read its triangles.
bool trianglesConsumed(GeometryKind a, GeometryKind b, const CulledKinds& kinds);

/// Whether the culler decides a pair that reads no triangles, with `kinds.gimpactVsConvex` set: a GImpact mesh
/// against a convex shape (a hull, a compound of convex children, or a convex primitive: `convexA`/`convexB`). The
/// culler proves AABB-overlapping pairs apart and a pair it keeps runs the dispatcher's GImpact-convex loop; measured
/// on the CPU path the culling costs more than the loop it saves (docs/drop-in.md, session 17), hence off by default.
bool prunedByCuller(GeometryKind a, bool convexA, GeometryKind b, bool convexB, const CulledKinds& kinds);

/// One object of the culling frame as the margin rule sees it.
struct MarginEntry {
    GeometryKind kind = GeometryKind::None;
    /// The collision margin of its triangles: GImpact and compounds triangleMarginOf, hulls and meshes getMargin.
    double margin = 0.0;
    double motionDisc = 0.0;  ///< btCollisionShape::getAngularMotionDisc()
    /// Not static, or static and pairing with other static objects: every pair has a member with this set.
    bool moving = false;
    /// Largest |AABB coordinate| (moving objects with triangle geometry; 0 otherwise): float slack of GImpact.
    double coordinate = 0.0;
};

/// How the dispatcher breaks contacts: gContactBreakingThreshold, scaled per pair by the smaller angular motion disc
/// when CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD is set (Bullet's default). `epsilon`: btScalar's.
struct BreakingRule {
    double threshold = 0.02;
    bool relative = true;
    double epsilon = 1.1920928955078125e-07;
};

/// The culler's distance margin d for a frame of these objects: every triangle pair that Bullet's narrow phase can
/// turn into a contact point, or keep one alive, is within d. Both collision margins plus the contact breaking
/// threshold t (relative: t times the smaller motion disc of the pair, bounded here by the frame's second-largest
/// disc and its largest disc of a `moving` entry). Algorithms with a persistent manifold (convex against mesh or convex) keep a
/// point while its normal distance and its tangential drift both stay within t, i.e. up to sqrt(2) t apart: 1.5 t.
/// GImpact rebuilds its manifold every frame; its triangle routine (btPrimitiveTriangle's clip method) reports
/// points within the sum of the two margins: 2.2 g plus float slack at the objects' coordinates. Box proxies carry
/// Bullet's AABB padding: 1.5 t among themselves. Never below 1e-9. Pure: the same entries give the same d.
double requiredCullingMargin(const std::vector<MarginEntry>& objects, const BreakingRule& rule);

/// The margin policy: given the margin this step `required` (requiredCullingMargin), the culler's `current` margin,
/// the application's `requested` Settings::margin (0: none), the step number (1 = first) and whether making a
/// smaller culler failed before, the margin to recreate the culler with — or nothing: keep the current one. The
/// culler is recreated when its margin is too small, and when it is more than twice what the scene needs (a margin
/// twice too large multiplies the within-margin triangle pairs the exact stage tests); after the first step with
/// 25% headroom, so that a slowly changing scene does not recreate it every step. Never below `requested`; a
/// culler that is large enough is kept when it is the requested margin or a smaller one could not be made.
std::optional<double> cullingMarginToMake(double required, double current, double requested, std::uint64_t step,
                                          bool shrinkFailed);

}  // namespace cullide::bullet
