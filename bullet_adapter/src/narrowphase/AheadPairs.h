// Which pairs of a dispatch the narrow-phase threads compute ahead (MeshContactBatch) while the calling thread runs
// the dispatch loop: GImpact mesh-mesh pairs the dispatch runs with Bullet's contacts, and GImpact-convex pairs whose
// per-triangle algorithm may run on a worker.
#pragma once

#include "narrowphase/NarrowPhaseContext.h"
#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <cstddef>

namespace cullide::bullet {

/// GImpact-convex pairs are computed ahead when the previous step ran at least this many of their triangles (~40 us
/// of GJK on the 2-core machine, about what waking the workers costs) or the batch runs anyway for mesh-mesh pairs.
constexpr std::size_t kMinAheadConvexTriangles = 64;

/// What decides the list besides the pair cache.
struct AheadInputs {
    btCollisionDispatcher& dispatcher;
    const CreateFuncTable& funcs;   ///< the dispatcher's double-dispatch table (contact point algorithms)
    unsigned threads = 1;           ///< narrow-phase threads in use
    bool gimpactPairCulling = false;    ///< the broadphase's switches (a culled pair reads the culler's record)
    bool gimpactConvexCulling = false;
    std::size_t lastConvexTriangles = 0;  ///< GImpact-convex triangles collided in the previous step
};

/// Fills `context.meshContacts` (cleared first) with the pairs of `pairCache` that the dispatch will run through the
/// adapter's GImpact algorithms with Bullet's contacts and that the workers can compute ahead; false when there are
/// none (then nothing is worth waking the workers for).
bool listAheadPairs(btOverlappingPairCache& pairCache, const btDispatcherInfo& dispatchInfo, const AheadInputs& in,
                    NarrowPhaseContext& context);

}  // namespace cullide::bullet
