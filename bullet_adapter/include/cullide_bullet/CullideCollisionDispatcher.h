// CullideCollisionDispatcher: a drop-in btCollisionDispatcher that hands each pair to Bullet's narrow phase the way
// Bullet would, except where CullideBroadphase's verdict or a cheaper reproduction of Bullet's own loop gives the same
// points for less: GImpact pairs (against GImpact, concave, convex and plane shapes) and, with convex-mesh culling,
// hulls against triangle meshes get the adapter's algorithms (one per pair kind); pairs whose boxes are farther apart
// than their breaking threshold skip their algorithm; Bullet's own algorithms run on narrow-phase threads where that
// leaves the manifolds bit for bit as Bullet's. bullet_adapter/README.md describes the guarantees and the known
// differences.
#pragma once

#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideStats.h"
#include "cullide_bullet/Precision.h"

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <cstddef>
#include <memory>

class btCollisionConfiguration;

namespace cullide {
class TaskPool;
namespace bullet {
enum class AlgorithmKind : int;
class AlgorithmTable;
struct NarrowPhaseContext;
}  // namespace bullet

class CullideCollisionDispatcher : public btCollisionDispatcher {
public:
    /// `broadphase` may be null (then this behaves exactly like btCollisionDispatcher) or set later.
    explicit CullideCollisionDispatcher(btCollisionConfiguration* collisionConfiguration,
                                        CullideBroadphase* broadphase = nullptr)
        : CullideCollisionDispatcher(detail::checkBulletPrecision(), collisionConfiguration, broadphase) {}
    ~CullideCollisionDispatcher() override;

    btCollisionAlgorithm* findAlgorithm(const btCollisionObjectWrapper* body0Wrap,
                                        const btCollisionObjectWrapper* body1Wrap,
                                        btPersistentManifold* sharedManifold,
                                        ebtDispatcherQueryType queryType) override;
    void dispatchAllCollisionPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                                   btDispatcher* dispatcher) override;
    void* allocateCollisionAlgorithm(int size) override;

    void setCullideBroadphase(CullideBroadphase* broadphase);
    CullideBroadphase* getCullideBroadphase() const { return m_broadphase; }

    /// Statistics of the last dispatchAllCollisionPairs() with the broadphase's own pair cache (one step).
    const CullideDispatchStats& getLastStepStats() const { return m_lastStep; }
    /// Accumulated over every call since the last resetStats().
    const CullideDispatchStats& getTotalStats() const { return m_total; }
    void resetStats() { m_total.reset(); }

    /// Threads for the narrow phase (0, the default: the machine's hardware threads, at most 8, read once per
    /// process; 1: none besides the calling one). With more than one, the contacts of the dispatch's
    /// btGImpactMeshShape pairs are computed on a worker pool — many pairs, and the parts of a large pair's box-tree
    /// search — while the calling thread runs the dispatch loop, where each pair's algorithm adds its points to the
    /// manifold in Bullet's order; and pairs whose Bullet algorithm touches only its own manifold (convex GJK pairs,
    /// convex against a BVH mesh or heightfield) run on the pool while the calling thread runs the others in the
    /// cache's order. The manifolds are the same bit for bit for every thread count: manifolds are made and freed,
    /// Bullet's pools used and the application's callbacks called on the calling thread only. More than
    /// kMaxNarrowPhaseThreads throws std::invalid_argument (the setting is left as it was).
    void setNarrowPhaseThreads(unsigned threads);
    static constexpr unsigned kMaxNarrowPhaseThreads = 256;  ///< as cullide::Settings::threads
    unsigned getNarrowPhaseThreads() const { return m_threads; }

private:
    /// The thread count in use (setNarrowPhaseThreads; 0 read as the machine's) and the pool of that many.
    unsigned narrowPhaseThreads() const;
    TaskPool& pool(unsigned threads);
    /// The kind of the pair's algorithm if it may run on a narrow-phase thread in this dispatch, else Other
    /// (src/ThreadedPairs.h).
    bullet::AlgorithmKind threadablePair(btBroadphasePair& pair);
    /// Lists the pairs the worker pool computes ahead while the dispatch runs (AheadPairs.h); false when none.
    bool listAheadPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo);
    /// Ends a dispatch: its counters into the step's (own cache) and total figures.
    void finishDispatch(bool ownCache, const btOverlappingPairCache* pairCache, double ms);
    /// The dispatch loop over the broadphase's own pair cache (discrete dispatch, Bullet's near callback): pairs
    /// apart skipped, threadable pairs handed to the workers when `mayStream` (the pool is free) and it pays.
    void dispatchOwnPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                          btDispatcher* dispatcher, bool mayStream);

    CullideCollisionDispatcher(detail::PrecisionChecked, btCollisionConfiguration* collisionConfiguration,
                               CullideBroadphase* broadphase);

    CullideBroadphase* m_broadphase;
    /// What the adapter's algorithms get at creation: the dispatch's counters, the GImpact leaf index, the contacts
    /// computed ahead, the broadphase's records.
    std::unique_ptr<bullet::NarrowPhaseContext> m_context;
    std::unique_ptr<bullet::AlgorithmTable> m_algorithms;
    CullideDispatchStats m_lastStep;
    CullideDispatchStats m_total;
    std::unique_ptr<TaskPool> m_pool;  // made on first use, for m_threads
    btManifoldArray m_manifoldScratch;
    /// The last dispatch's pairs that could run on the narrow-phase threads, in bullet::typicalCost units: this
    /// dispatch wakes the workers from kMinThreadedCost on.
    std::size_t m_lastThreadableCost = 0;
    unsigned m_dispatchesSinceCount = 0;
    bool m_poolBusy = false;  // the worker pool serves a dispatch under way
    static constexpr std::size_t kMinThreadedCost = 300;
    static constexpr unsigned kRecountDispatches = 16;
    unsigned m_threads = 0;
};

}  // namespace cullide
