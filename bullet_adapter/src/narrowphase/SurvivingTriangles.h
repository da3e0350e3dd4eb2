// A triangle mesh as the culler left it for one pair: a stand-in concave shape that enumerates only the record's
// surviving triangles (mesh-local vertices as processAllTriangles yields them, Bullet's part and triangle ids), and a
// wrapper of the mesh's object with the stand-in as its shape. Both live on the stack for one processCollision call.
#pragma once

#include "broadphase/PairTriangles.h"

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>

#include <cstddef>
#include <vector>

namespace cullide::bullet {

class SurvivingTrianglesShape final : public btConcaveShape {
public:
    SurvivingTrianglesShape(const btConcaveShape& mesh, const PairTriangles& triangles)
        : m_mesh(mesh), m_triangles(triangles) {
        m_shapeType = mesh.getShapeType();
        setMargin(mesh.getMargin());
    }

    void processAllTriangles(btTriangleCallback* callback, const btVector3& /*aabbMin*/,
                             const btVector3& /*aabbMax*/) const override {
        btVector3 triangle[3];
        const std::vector<btVector3>& v = m_triangles.meshTriangleVertices;
        for (std::size_t i = 0; i < m_triangles.meshTriangles.size(); ++i) {
            triangle[0] = v[3 * i];
            triangle[1] = v[3 * i + 1];
            triangle[2] = v[3 * i + 2];
            callback->processTriangle(triangle, m_triangles.meshTriangles[i].part, m_triangles.meshTriangles[i].index);
        }
    }
    void getAabb(const btTransform& t, btVector3& aabbMin, btVector3& aabbMax) const override {
        m_mesh.getAabb(t, aabbMin, aabbMax);
    }
    void setLocalScaling(const btVector3& /*scaling*/) override {}
    const btVector3& getLocalScaling() const override { return m_mesh.getLocalScaling(); }
    void calculateLocalInertia(btScalar /*mass*/, btVector3& inertia) const override { inertia.setValue(0, 0, 0); }
    const char* getName() const override { return "CullideSurvivingTriangles"; }

private:
    const btConcaveShape& m_mesh;
    const PairTriangles& m_triangles;
};

/// A triangle mesh's wrapper with the mesh replaced by its surviving triangles (same object, transform and ids).
struct SurvivingMeshWrapper {
    SurvivingMeshWrapper(const btCollisionObjectWrapper* meshWrap, const PairTriangles& triangles)
        : shape(*static_cast<const btConcaveShape*>(meshWrap->getCollisionShape()), triangles),
          wrapper(meshWrap->m_parent, &shape, meshWrap->getCollisionObject(), meshWrap->getWorldTransform(),
                  meshWrap->m_partId, meshWrap->m_index) {}
    SurvivingTrianglesShape shape;
    btCollisionObjectWrapper wrapper;
};

}  // namespace cullide::bullet
