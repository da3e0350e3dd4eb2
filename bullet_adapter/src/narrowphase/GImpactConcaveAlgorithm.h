// GImpact shape against a concave shape that is neither GImpact nor a plane (btBvhTriangleMeshShape, its scaled
// form, btHeightfieldTerrainShape, ...; either order).
// - Not culled (the default): for a GImpact mesh, Bullet's contacts point for point — Bullet's gimpact_vs_concave per
//   mesh part in Bullet's order (the concave shape's triangles within the part's box, each as a triangle shape
//   against the part through Bullet's per-triangle loop, with Bullet's shape identifiers and result wrappers) minus,
//   for each concave triangle, the part's candidates that cannot make a point with it (Bullet runs GJK on each).
//   A GImpact compound or lone part: Bullet's algorithm as it is.
// - Culled (CullideBroadphase::setGImpactMeshCulling): Bullet's gimpact_vs_shape against a stand-in mesh that
//   enumerates the record's surviving triangles (SurvivingTriangles.h).
#pragma once

#include "narrowphase/GImpactAlgorithmBase.h"

namespace cullide::bullet {

class GImpactConcaveAlgorithm final : public GImpactAlgorithmBase {
public:
    using GImpactAlgorithmBase::GImpactAlgorithmBase;

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;

private:
    /// The not-culled path for a GImpact mesh (see above). `swapped`: the concave shape is the pair's first body.
    void processWithBulletContacts(const btCollisionObjectWrapper* gimpactWrap,
                                   const btCollisionObjectWrapper* concaveWrap, bool swapped,
                                   const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut);
    /// The culled path: the record's surviving mesh triangles.
    void processSurvivors(const btCollisionObjectWrapper* gimpactWrap, const btCollisionObjectWrapper* concaveWrap,
                          bool swapped, const PairTriangles& triangles, const btDispatcherInfo& dispatchInfo,
                          btManifoldResult* resultOut);

    class ConcaveTriangles;
};

}  // namespace cullide::bullet
