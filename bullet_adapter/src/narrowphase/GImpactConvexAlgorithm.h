// GImpact mesh against a convex shape that is not a compound (box, sphere, hull, ...; either order): Bullet's own
// per-triangle loop — its box query of each mesh part with the convex shape's box in the part's frame, then every
// candidate triangle against the convex shape through the dispatcher's convex algorithm, in Bullet's order and with
// Bullet's shape identifiers — minus the candidates that cannot make a point (bullet::convexCanTouch). Bullet's query
// box is the convex shape's AABB in the mesh's frame, which for a large or rotated convex shape (a ground box) holds
// most of the mesh, and every candidate costs a GJK run. The contacts are Bullet's: a skipped triangle is farther from
// the convex shape than btManifoldResult accepts a point. With GImpact-convex culling on, a pair the culler proved out
// of reach makes no point that step. The points may come from the batch the narrow-phase threads computed ahead.
#pragma once

#include "narrowphase/GImpactAlgorithmBase.h"

namespace cullide::bullet {

class GImpactConvexAlgorithm final : public GImpactAlgorithmBase {
public:
    using GImpactAlgorithmBase::GImpactAlgorithmBase;

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;

private:
    /// The pair's points computed ahead by the dispatch's batch (bullet::convexChunkContacts), or nullptr.
    const bullet::MeshContactBatch::ConvexAhead* convexAhead(const btCollisionObjectWrapper* body0Wrap,
                                                             const btCollisionObjectWrapper* body1Wrap,
                                                             const btDispatcherInfo& dispatchInfo) const;
};

}  // namespace cullide::bullet
