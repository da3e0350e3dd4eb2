// Robust triangle-triangle tests on closed triangles (touching counts), with degenerate triangles allowed.
#pragma once

#include "cullide/Types.h"

namespace cullide {

/// Exact: true iff closed triangles (a0,a1,a2) and (b0,b1,b2) share at least one point. Zero-area and collinear
/// triangles (segments, points) are handled. A floating-point filter decides most cases; the rest are decided by
/// exact expansion arithmetic on the double inputs. Inputs must be finite.
bool trianglesIntersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                        const Vec3& b2);

/// Euclidean distance between two closed triangles (0 when they intersect), in double precision.
double triangleDistance(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                        const Vec3& b2);

/// The culler's exact-stage predicate: intersect (exact) or, with margin > 0, distance <= margin.
bool trianglesWithin(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                     const Vec3& b2, double margin);

}  // namespace cullide
