// What the broadphase hands to the culler, as pure functions of the shapes: which object pairs go through the
// CULLIDE levels, and the distance margin d those pairs need. Unit-tested without Bullet worlds.
#pragma once

#include "broadphase/ShapeGeometry.h"
#include "cullide_bullet/CullideBroadphase.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace cullide::bullet {

/// The culling switch that covers a pair of objects of these geometry kinds (`convexA`/`convexB`: the shape is
/// convex, for an object without triangle geometry), if any: GImpact-GImpact, GImpact-triangle mesh, GImpact-convex
/// (a hull, a compound of convex children or a convex primitive), hull or compound-triangle mesh. Every other pair
/// (primitives, hull-hull, planes, ...) goes from the object level straight to the dispatcher's algorithms.
std::optional<CulledKind> culledKindOf(GeometryKind a, bool convexA, GeometryKind b, bool convexB);

/// The kinds culled in a step (CulledKind order).
struct CulledKinds {
    std::array<bool, 4> on{};
    bool operator[](CulledKind k) const { return on[static_cast<std::size_t>(k)]; }
    void set(CulledKind k, bool value) { on[static_cast<std::size_t>(k)] = value; }
    /// Whether any kind is culled: with none no pair goes through the culler.
    bool any() const { return on[0] || on[1] || on[2] || on[3]; }
};

/// One object of the culling frame as the margin rule sees it.
struct MarginEntry {
    GeometryKind kind = GeometryKind::None;
    /// The collision margin of its triangles: GImpact and compounds triangleMarginOf, hulls and meshes getMargin.
    double margin = 0.0;
    double motionDisc = 0.0;  ///< btCollisionShape::getAngularMotionDisc()
    /// Largest |AABB coordinate| (objects with triangle geometry; 0 otherwise): the float slack of Bullet's
    /// arithmetic against the culler's there.
    double coordinate = 0.0;
};

/// How the dispatcher breaks contacts: gContactBreakingThreshold, scaled per pair by the smaller angular motion disc
/// when CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD is set (Bullet's default). `epsilon`: btScalar's.
struct BreakingRule {
    double threshold = 0.02;
    bool relative = true;
    double epsilon = 1.1920928955078125e-07;
};

/// The culling margin rule, the one place it is stated. The reach of a culled pair is the largest distance between
/// two of its triangles from which Bullet's narrow phase for the pair can make a contact point that the culled path
/// must reproduce, plus the float slack between Bullet's arithmetic and the culler's at the objects' coordinates
/// (8 epsilon times the largest coordinate). With t the pair's contact breaking threshold (getNewManifold's: the
/// threshold times the smaller angular motion disc when relative) and g, m, c the margins of a GImpact mesh, a
/// triangle mesh and a convex shape:
/// - GImpact mesh - GImpact mesh: 1.1 (g_a + g_b). Bullet's clip method makes a point from a triangle pair where
///   each triangle reaches into the other's prism no higher than g_a + g_b above the other's plane; a point above a
///   plane therefore comes from triangles within g_a + g_b of each other. A point on or below a plane can come from
///   any pair Bullet's box-set search tests (the meshes interpenetrate, or a triangle lies behind the other within
///   their overlapping boxes): the culled path falls back to Bullet's contacts for a pair whose kept triangles
///   intersect (CullideBroadphase::setDeepPenetrationFallback) and for a pair whose kept triangles make no point, so
///   every pair Bullet gives a point gets one. The contact breaking threshold plays no part: GImpact rebuilds its
///   manifold every step.
/// - GImpact mesh - triangle mesh or convex shape: GJK per triangle pair, a point kept within t of the
///   margin-grown shapes, the manifold rebuilt every step: g + m + t (g + c + t; a convex primitive is culled as its
///   box, which holds its margin).
/// - Convex hull or compound - triangle mesh: a persistent manifold keeps a point while its normal distance and its
///   drift both stay within t, i.e. up to sqrt(2) t apart: c + m + 1.5 t.
/// Never below 1e-9. Pure: the same entries give the same reach.
double pairReach(const MarginEntry& a, const MarginEntry& b, const BreakingRule& rule);

/// The culler's distance margin for a frame: the largest reach of its pairs (indices into `objects`), so that every
/// triangle pair of a culled pair that Bullet's narrow phase could use survives culling.
double requiredCullingMargin(const std::vector<MarginEntry>& objects,
                             const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                             const BreakingRule& rule);

/// The margin policy: given the margin this step `required` (requiredCullingMargin), the culler's `current` margin,
/// the application's `requested` Settings::margin (0: none), the step number (1 = first) and whether making a
/// smaller culler failed before, the margin to recreate the culler with — or nothing: keep the current one. The
/// culler is made with 25% headroom over what the frame needs (the float slack and the pairs in the frame change
/// from step to step: a culler fitted exactly would be remade for every small growth), and recreated when its margin
/// is too small, and when it is more than twice what the scene needs (a margin twice too large multiplies the
/// within-margin triangle pairs the exact stage tests), or on the first step more than the headroom above it (the
/// constructor's default). Never below `requested`; a culler that is large enough is kept when it is the requested
/// margin or a smaller one could not be made.
std::optional<double> cullingMarginToMake(double required, double current, double requested, std::uint64_t step,
                                          bool shrinkFailed);

}  // namespace cullide::bullet
