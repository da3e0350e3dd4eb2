// Triangle geometry of Bullet shapes in the shape's local frame, as Bullet's narrow phase sees it.
#pragma once

#include "cullide/Types.h"
#include "broadphase/PairTriangles.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <LinearMath/btVector3.h>

#include <cstdint>
#include <memory>
#include <vector>

class btCollisionShape;
class btTriangleMeshShape;

namespace cullide::bullet {

enum class GeometryKind {
    None,         ///< no triangle geometry: the culler sees the broadphase AABB
    GImpactMesh,  ///< btGImpactMeshShape (CONST_GIMPACT_TRIMESH_SHAPE)
    TriangleMesh, ///< btBvhTriangleMeshShape / btTriangleMeshShape (TRIANGLE_MESH_SHAPE_PROXYTYPE), and
                  ///< btScaledBvhTriangleMeshShape (its scaling applied to the child's triangles, as Bullet does)
    ConvexHull,   ///< btConvexHullShape: the hull of its scaled points
    Compound,     ///< btCompoundShape of convex children (nested compounds too): hull children as their hulls,
                  ///< other convex children as their local boxes (12 triangles, margin included), in the
                  ///< compound's frame. A compound with a concave child has no triangle geometry.
};

GeometryKind geometryKindOf(const btCollisionShape* shape);

/// The triangle mesh shape behind `shape`: itself, or a scaled wrapper's child; nullptr for any other shape.
const btTriangleMeshShape* triangleMeshOf(const btCollisionShape* shape);

/// True for the shape types of GeometryKind::TriangleMesh (plain and scaled BVH / triangle meshes).
inline bool isTriangleMeshType(int shapeType) {
    return shapeType == TRIANGLE_MESH_SHAPE_PROXYTYPE || shapeType == SCALED_TRIANGLE_MESH_SHAPE_PROXYTYPE;
}

struct ShapeTriangles {
    GeometryKind kind = GeometryKind::None;
    const btCollisionShape* shape = nullptr;
    btVector3 scaling{1, 1, 1};  ///< scaling it was built with (change detection)
    int sourceCount = 0;         ///< vertex/point count it was built from (change detection)
    std::uint64_t sourceHash = 0; ///< content hash of the vertex/index/point data it was built from (deformation)
    /// Local vertices computed exactly as Bullet computes them (btScalar precision, scaling applied).
    std::vector<btVector3> vertices;
    std::vector<TriangleIndices> triangles;
    std::vector<BulletTriangle> refs;  ///< Bullet's (part, index) of each triangle
    btScalar margin = 0;               ///< largest collision margin Bullet uses for these triangles
    /// `vertices` (exactly, in double) and `triangles` as the culler's local mesh: every moving body with this shape
    /// hands it over with its world transform (Object::transform), so the mesh is held once per shape.
    TriangleMesh local;
};

/// Content hash of the data a shape's triangles are built from (vertex/index data, hull points): detects in-place
/// deformation. About 50 us per 20K vertices; callers compute it once per shape and step.
std::uint64_t sourceHashOf(const btCollisionShape* shape);

/// Builds the local triangle geometry of `shape` (whose content hash is `sourceHash`), or nullptr when it has none.
std::shared_ptr<ShapeTriangles> buildShapeTriangles(const btCollisionShape* shape, std::uint64_t sourceHash);

/// True while `geometry` still describes `shape`: same pointer, kind, scaling, source size and content hash.
bool stillMatches(const ShapeTriangles& geometry, const btCollisionShape* shape, std::uint64_t sourceHash);

/// The collision margin Bullet applies to the shape's triangles (GImpact: the parts' margins; compounds: the
/// largest of their children's).
btScalar triangleMarginOf(const btCollisionShape* shape);

}  // namespace cullide::bullet
