// Procedural meshes shared by tests, benchmarks and demos.
#pragma once

#include "cullide/Types.h"

#include <Eigen/Geometry>

#include <cstdint>

namespace cullide::scenes {

/// Torus around the z axis: major radius R, minor radius r, nu x nv quads (2*nu*nv triangles).
TriangleMesh makeTorus(double R, double r, int nu, int nv);
/// Open cylinder along z (no caps), centred at the origin: `segments` around, `rings` along (2*segments*rings tris).
TriangleMesh makeOpenCylinder(double radius, double height, int segments, int rings);
/// UV sphere, closed: 2*nu*(nv-1) triangles.
TriangleMesh makeSphere(double radius, int nu, int nv);
/// Closed axis-aligned box, 12 triangles.
TriangleMesh makeBox(const Vec3& halfExtents);
/// Applies an affine transform to every vertex.
void transformMesh(TriangleMesh& mesh, const Eigen::Affine3d& t);
/// Bounding box of the mesh's vertices.
Aabb boundsOf(const TriangleMesh& mesh);

}  // namespace cullide::scenes
