// What every algorithm of the adapter gets when the dispatcher makes it: the dispatch's counters, the GImpact leaf
// index, the contacts computed ahead on the narrow-phase threads, and the broadphase's records of the step. The
// dispatcher owns one context for its lifetime (its address never changes) and keeps `records` pointing at its
// broadphase's.
#pragma once

#include "cullide_bullet/CullideStats.h"
#include "narrowphase/GImpactLeafIndex.h"
#include "narrowphase/GImpactMeshContacts.h"

class btCollisionObjectWrapper;

namespace cullide {
struct PairTriangles;
namespace bullet {

class PairRecords;

struct NarrowPhaseContext {
    /// Counters of the dispatch under way (CullideCollisionDispatcher sums them into its step and total figures).
    CullideDispatchStats stats;
    /// Primitive -> leaf node of GImpact box sets (Bullet's candidate criterion for culled mesh-mesh pairs).
    GImpactLeafIndex leafIndex;
    /// GImpact mesh-mesh and GImpact-convex contacts computed on the narrow-phase threads during the dispatch.
    bullet::MeshContactBatch meshContacts;
    /// The broadphase's records of the step (nullptr without a CullideBroadphase).
    const PairRecords* records = nullptr;

    /// The record of the wrapped objects' pair while it holds (PairRecords::find), else nullptr: Bullet's algorithm
    /// must run. `swapped` is set when w0 is the record's second object.
    const PairTriangles* recordFor(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                                   bool& swapped) const;
};

}  // namespace bullet
}  // namespace cullide
