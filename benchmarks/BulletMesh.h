// Meshes, poses and environment objects handed to Bullet by the benchmarks (cullide-bench-run's Bullet engine, cullide-swap-bench's
// collision worlds): the same conversions, so both model an environment the same way.
#pragma once

#include "BenchScene.h"
#include "cullide/Types.h"

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btTransform.h>

#include <Eigen/Geometry>

#include <cmath>
#include <memory>
#include <vector>

namespace cullide::bench {

inline btTransform toBullet(const Eigen::Isometry3d& pose) {
    const Eigen::Matrix3d r = pose.rotation();
    const Eigen::Vector3d t = pose.translation();
    const btMatrix3x3 basis(btScalar(r(0, 0)), btScalar(r(0, 1)), btScalar(r(0, 2)), btScalar(r(1, 0)),
                            btScalar(r(1, 1)), btScalar(r(1, 2)), btScalar(r(2, 0)), btScalar(r(2, 1)),
                            btScalar(r(2, 2)));
    return btTransform(basis, btVector3(btScalar(t.x()), btScalar(t.y()), btScalar(t.z())));
}

/// The mesh's vertices as btScalar xyz triples (rewritten in place when an object deforms).
inline void copyVertices(const TriangleMesh& mesh, std::vector<btScalar>& out) {
    out.resize(3 * mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
        for (int k = 0; k < 3; ++k) out[3 * i + static_cast<std::size_t>(k)] = static_cast<btScalar>(mesh.vertices[i][k]);
}

/// A torus around the y axis (ring radius R, tube radius r) as btScalar xyz triples and triangle indices appended to
/// `v` and `idx`: segments x sides quads, two triangles each.
inline void torusArrays(double R, double r, int segments, int sides, std::vector<btScalar>& v, std::vector<int>& idx) {
    const int first = static_cast<int>(v.size() / 3);
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const double u = 2 * M_PI * i / segments, w = 2 * M_PI * j / sides;
            v.insert(v.end(), {btScalar((R + r * std::cos(w)) * std::cos(u)), btScalar(r * std::sin(w)),
                               btScalar((R + r * std::cos(w)) * std::sin(u))});
        }
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const int a = i * sides + j, b = ((i + 1) % segments) * sides + j;
            const int c = ((i + 1) % segments) * sides + (j + 1) % sides, d = i * sides + (j + 1) % sides;
            idx.insert(idx.end(), {first + a, first + b, first + c, first + a, first + c, first + d});
        }
}

/// A btTriangleIndexVertexArray over `vertices` (see copyVertices) and the mesh's triangles (written to `indices`);
/// both vectors must outlive the array and keep their storage.
inline std::unique_ptr<btTriangleIndexVertexArray> indexedMesh(const TriangleMesh& mesh,
                                                               const std::vector<btScalar>& vertices,
                                                               std::vector<int>& indices) {
    indices.clear();
    for (const auto& t : mesh.triangles)
        for (std::uint32_t k : t) indices.push_back(static_cast<int>(k));
    btIndexedMesh part;
    part.m_numTriangles = static_cast<int>(mesh.triangles.size());
    part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(indices.data());
    part.m_triangleIndexStride = 3 * static_cast<int>(sizeof(int));
    part.m_numVertices = static_cast<int>(vertices.size() / 3);
    part.m_vertexBase = reinterpret_cast<const unsigned char*>(vertices.data());
    part.m_vertexStride = 3 * static_cast<int>(sizeof(btScalar));
    part.m_indexType = PHY_INTEGER;
    part.m_vertexType = sizeof(btScalar) == sizeof(float) ? PHY_FLOAT : PHY_DOUBLE;
    auto array = std::make_unique<btTriangleIndexVertexArray>();
    array->addIndexedMesh(part, PHY_INTEGER);
    return array;
}

/// One object of an environment as a Bullet collision object with a GImpact shape of margin 0 (the task is the
/// intersecting triangle pairs), and the mesh arrays the shape reads. Static and rigid objects hold their frame-0
/// mesh and move by transform; deforming ones hold world-space vertices, rewritten every frame.
struct GImpactBody {
    std::vector<btScalar> vertices;
    std::vector<int> indices;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btGImpactMeshShape> shape;
    std::unique_ptr<btCollisionObject> object;
    Motion motion = Motion::Deforming;

    /// Object `i` of the first frame (user index i); the caller adds it to its world.
    void build(const BenchFrame& first, std::size_t i) {
        motion = (*first.motion)[i];
        const TriangleMesh& mesh = motion == Motion::Deforming ? (*first.world)[i] : (*first.local)[i];
        copyVertices(mesh, vertices);
        array = indexedMesh(mesh, vertices, indices);
        shape = std::make_unique<btGImpactMeshShape>(array.get());
        shape->setMargin(0);
        shape->updateBound();
        object = std::make_unique<btCollisionObject>();
        object->setCollisionShape(shape.get());
        object->setUserIndex(static_cast<int>(i));
        object->setWorldTransform(motion == Motion::Deforming ? btTransform::getIdentity() : toBullet(first.poses[i]));
    }

    /// Object `i`'s state in `frame`: new vertices (postUpdate + updateBound) or a new transform.
    void move(const BenchFrame& frame, std::size_t i) {
        if (motion == Motion::Deforming) {
            copyVertices((*frame.world)[i], vertices);
            shape->postUpdate();
            shape->updateBound();
        } else if (motion == Motion::Rigid) {
            object->setWorldTransform(toBullet(frame.poses[i]));
        }
    }
};

}  // namespace cullide::bench
