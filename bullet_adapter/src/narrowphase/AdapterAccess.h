// The calls between the adapter's broadphase, dispatcher and algorithms that are not part of the public API: the
// public classes befriend this one struct, so that applications see none of them.
#pragma once

#include "broadphase/PairTriangles.h"
#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

namespace cullide::detail {

struct AdapterAccess {
    /// The broadphase's record of the wrapped objects' pair (PairRecords::find).
    static const PairTriangles* trianglePairsFor(const CullideBroadphase& broadphase, const btCollisionObjectWrapper* w0,
                                                 const btCollisionObjectWrapper* w1, bool& swapped) {
        return broadphase.trianglePairsFor(w0, w1, swapped);
    }
    static CullideDispatchStats& currentStats(CullideCollisionDispatcher& d) { return d.currentStats(); }
    static GImpactLeafIndex& gimpactLeafIndex(CullideCollisionDispatcher& d) { return d.gimpactLeafIndex(); }
    static MeshContactBatch& meshContacts(CullideCollisionDispatcher& d) { return d.meshContacts(); }
};

}  // namespace cullide::detail
