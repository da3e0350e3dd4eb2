// A convex hull, or a compound's convex child, against a triangle mesh (btBvhTriangleMeshShape, btTriangleMeshShape,
// scaled), culled (CullideBroadphase::setConvexMeshCulling): Bullet's btConvexConcaveCollisionAlgorithm
// (btConvexTriangleCallback, persistent manifold) driven with the record's surviving mesh triangles only. A pair
// without a record this step, or a result that keeps points beyond the breaking threshold, runs Bullet's algorithm
// on every triangle.
#pragma once

#include "narrowphase/NarrowPhaseContext.h"

#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>

namespace cullide::bullet {

/// MeshFirst: the mesh is the pair's first body (Bullet's SwappedCreateFunc).
template <bool MeshFirst>
class ConvexMeshAlgorithm final : public btConvexConcaveCollisionAlgorithm {
public:
    ConvexMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* body0Wrap,
                        const btCollisionObjectWrapper* body1Wrap, NarrowPhaseContext& context)
        : btConvexConcaveCollisionAlgorithm(ci, body0Wrap, body1Wrap, MeshFirst), m_context(context) {}

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;

private:
    NarrowPhaseContext& m_context;
};

extern template class ConvexMeshAlgorithm<false>;
extern template class ConvexMeshAlgorithm<true>;

}  // namespace cullide::bullet
