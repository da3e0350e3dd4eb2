// GImpact mesh against a static plane (either order), where Bullet's algorithm collides the two by the mesh's
// vertices (GIMPACT_VS_PLANE_COLLISION): Bullet's gimpact_vs_shape for a mesh and a plane — each part, last to first,
// through its vertex loop (gimpacttrimeshpart_vs_plane_collision) — with the vertices that cannot make a point ruled
// out first by a cheaper bound (GImpactPlaneContacts.h). Same points, same order. The culler keeps no record for
// these pairs: none is looked up.
#pragma once

#include "narrowphase/GImpactAlgorithmBase.h"

namespace cullide::bullet {

class GImpactPlaneAlgorithm final : public GImpactAlgorithmBase {
public:
    using GImpactAlgorithmBase::GImpactAlgorithmBase;

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override;
};

}  // namespace cullide::bullet
