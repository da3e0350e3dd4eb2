// Fracture for the breakable-object demo: a triangle soup is cut into the Voronoi cells of a set of sites (open,
// cut meshes: cells are not capped, as the culler takes triangle soups as they are), and each piece gets rigid-body
// mass properties from its convex hull. Pure geometry, deterministic, no GL.
#pragma once

#include "cullide/Types.h"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace cullide::demo {

/// Sites for a fracture at `impact` inside `bounds`: half of them clustered around the impact (small pieces
/// there, as in a real impact), the rest spread over the box. Deterministic for `seed`. `count` >= 1.
std::vector<Vec3> fractureSites(const Aabb& bounds, const Vec3& impact, int count, std::uint64_t seed);

/// Cuts `mesh` into the Voronoi cells of `sites` (result i = cell of site i; may be empty). Triangles inside one cell
/// go to it whole; triangles crossing cells are clipped exactly (in double) and fanned. Every cell is shrunk by
/// gap / 2 on each face it shares with a neighbour, so pieces start `gap` apart and never touch at rest; triangles
/// of near-zero area (relative 1e-12 of the mesh's size squared; original or produced by clipping) are dropped.
/// Non-finite vertices and out-of-range indices are skipped.
std::vector<TriangleMesh> voronoiCut(const TriangleMesh& mesh, const std::vector<Vec3>& sites, double gap);

/// Rigid-body mass properties of the solid convex hull of `points` with uniform `density`.
struct MassProperties {
    double volume = 0.0;
    double mass = 0.0;
    Vec3 centre = Vec3::Zero();                           ///< centre of mass
    Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();   ///< principal axes (columns, right-handed)
    Vec3 inertia = Vec3::Zero();                          ///< principal moments about `centre`
    bool fromHull = true;  ///< false: the hull was (nearly) flat; a box around the points was used instead
};
/// Needs at least one finite point, density > 0 and minThickness > 0 (else std::invalid_argument). Flat or tiny
/// point sets fall back to their bounding box grown to at least `minThickness` per side, so every piece has a
/// positive mass and inertia.
MassProperties hullMassProperties(const std::vector<Vec3>& points, double density, double minThickness);

}  // namespace cullide::demo
