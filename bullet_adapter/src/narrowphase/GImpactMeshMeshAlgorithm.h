// GImpact mesh against GImpact mesh (two btGImpactMeshShapes).
// - Not culled (the default; also a culled pair whose meshes interpenetrate): Bullet's contacts bit for bit, from
//   Bullet's box-set pair search and triangle routine reproduced at a fraction of Bullet's cost
//   (bullet::meshPairContacts), or taken from the batch the narrow-phase threads computed ahead.
// - Culled (CullideBroadphase::setGImpactPairCulling): the record's surviving triangle pairs that Bullet's own
//   box-set search would also produce go to Bullet's triangle routine (collide_sat_triangles' loop); a pair whose
//   kept triangles make no point gets Bullet's contacts (CullingPolicy.h, pairReach, says why).
// A GImpact compound or a lone mesh part on either side runs Bullet's algorithm as it is.
#pragma once

#include "narrowphase/GImpactAlgorithmBase.h"

namespace cullide::bullet {

class GImpactMeshMeshAlgorithm final : public GImpactAlgorithmBase {
public:
    using GImpactAlgorithmBase::GImpactAlgorithmBase;

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;

private:
    /// Bullet's GImpact-GImpact algorithm, contact for contact: per part pair in Bullet's order, Bullet's box-set
    /// pairs in Bullet's order, through Bullet's own triangle routine, each triangle mapped to world space and given
    /// its planes once per call instead of once per pair it is in. The points come from the dispatch's batch when it
    /// computed them ahead for these inputs.
    void processWithBulletContacts(const btCollisionObjectWrapper* body0Wrap,
                                   const btCollisionObjectWrapper* body1Wrap, const btGImpactMeshShape& shape0,
                                   const btGImpactMeshShape& shape1, const btDispatcherInfo& dispatchInfo,
                                   btManifoldResult* resultOut);
    /// The record's surviving triangle pairs (not interpenetrating), part pair by part pair.
    void processSurvivors(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btGImpactMeshShape& shape0, const btGImpactMeshShape& shape1,
                          const PairTriangles& triangles, bool swapped);
};

}  // namespace cullide::bullet
