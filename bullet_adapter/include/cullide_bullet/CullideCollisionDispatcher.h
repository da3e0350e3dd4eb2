// CullideCollisionDispatcher: a btCollisionDispatcher that hands only CULLIDE's surviving triangle pairs to Bullet's
// narrow phase.
//
// - GImpact-GImpact (once the application called btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher), as it
//   must with Bullet's own dispatcher): a btGImpactCollisionAlgorithm subclass runs Bullet's triangle-triangle
//   routine (collide_sat_triangles) on the surviving triangle pairs that Bullet's own BVH search would also
//   produce; interpenetrating pairs run Bullet's full algorithm. GImpact vs triangle mesh: Bullet's
//   gimpact_vs_concave over the mesh's surviving triangles only.
// - Convex hull, or a compound's convex child, vs btBvhTriangleMeshShape / btTriangleMeshShape: a
//   btConvexConcaveCollisionAlgorithm subclass drives btConvexTriangleCallback with the mesh's surviving triangles.
// - GImpact mesh vs a convex shape (box, sphere, hull, ...; not a compound): Bullet's own per-triangle loop (its box
//   query, then each candidate triangle against the convex shape, in Bullet's order), minus the triangles farther
//   from the convex shape's local box than 1.5 * (triangle margin + contact breaking threshold): they cannot make a
//   point. Bullet's query box is the convex shape's AABB in the mesh's frame; for a ground box that is most of the
//   mesh, and every candidate costs a GJK run. The contacts are Bullet's, point for point.
// - GImpact mesh vs static plane: Bullet's vertex loop (gimpacttrimeshpart_vs_plane_collision), part by part, with
//   most vertices ruled out first by a bound read straight from the mesh's arrays (the plane in the mesh's frame,
//   less a bound on the rounding error of Bullet's arithmetic); the rest go through Bullet's test in Bullet's order.
//   The contacts are Bullet's, point for point.
// - A pair the broadphase recorded as pruned (the culler proved it farther apart than its margin) makes no contact:
//   its algorithm clears its manifold and returns. A pair recorded as interpenetrating runs Bullet's full algorithm.
// - Everything else (primitives, compound-compound and compound-convex per child, planes against anything but a
//   GImpact mesh, soft bodies) goes to Bullet's algorithms unchanged; so does any pair for which the broadphase has
//   no fresh triangle data (a character controller's private pair cache after the ghost moved, contactTest, another
//   broadphase).
// - GImpact mesh-mesh pairs computed with Bullet's contacts (the default) have their points computed on the
//   narrow-phase threads (setNarrowPhaseThreads) while the dispatch loop runs; each pair's algorithm adds them to its
//   manifold on the calling thread, in Bullet's order: the same manifolds for every thread count.
// - Pairs whose algorithm is Bullet's own and touches only its own manifold (GJK for convex shapes, convex against a
//   BVH mesh or heightfield; src/ThreadedPairs.h) run on the narrow-phase threads while the calling thread runs the
//   others in the pair cache's order: manifolds are made in Bullet's order, the simulation is Bullet's bit for bit.
//   Pairs that would call the application (contact callbacks, combiners, a drawing debug drawer) stay on the
//   calling thread.
// - A pair whose broadphase boxes are farther apart than its manifold's contact breaking threshold can make no
//   contact point: its algorithm is skipped and its manifolds' points are cleared, as btAxisSweep3 would drop the
//   pair (rigid and plain collision objects without GImpact shapes, discrete dispatch, Bullet's near callback;
//   src/ApartPairs.h). The pair cache stays the broadphase's.
// - Triangle pairs are processed in sorted order: contacts are deterministic.
// - Algorithms larger than the configuration's pool element are allocated from the heap, never from the pool.
#pragma once

#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/Precision.h"

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <cstddef>
#include <memory>

class btCollisionConfiguration;

namespace cullide {
namespace detail {
class GImpactLeafIndex;
class MeshContactBatch;
struct AdapterAccess;
}
class TaskPool;
namespace bullet {
enum class AlgorithmKind : int;
}

struct CullideDispatchStats {
    std::size_t pairsDispatched = 0;    ///< pairs in the dispatched caches (all dispatchAllCollisionPairs calls)
    std::size_t cullidePairs = 0;       ///< pairs processed from CULLIDE's triangle lists
    std::size_t trianglePairs = 0;      ///< triangle pairs (or mesh triangles for convex-mesh) handed over
    std::size_t fallbackPairs = 0;      ///< triangle-capable pairs given Bullet's full algorithm instead (its own, or
                                        ///< for GImpact-GImpact its reproduction with Bullet's contacts)
    std::size_t clearedPairs = 0;       ///< pairs with no surviving triangle: manifolds cleared
    std::size_t penetrationPairs = 0;   ///< interpenetrating GImpact pairs given Bullet's full algorithm (included
                                        ///< in cullidePairs; see CullideBroadphase::setDeepPenetrationFallback)
    /// GImpact mesh vs convex shape pairs (Bullet's per-triangle loop, minus triangles out of reach)
    std::size_t convexPairs = 0;
    /// GImpact mesh vs concave shape (triangle mesh, heightfield, plane) pairs not culled: Bullet's per-triangle loop
    /// for each concave triangle within reach, minus GImpact triangles out of reach of it
    std::size_t concavePairs = 0;
    std::size_t convexCandidates = 0;   ///< ... triangles of Bullet's box queries (both kinds of pair)
    std::size_t convexTriangles = 0;    ///< ... of which within reach of the convex shape: run through GJK
    /// ... of which taken without a per-triangle test: their mesh part lay wholly within reach of the convex shape
    /// (Bullet's absolute breaking threshold, 0.02, reaches across whole objects in a world of small units)
    std::size_t convexUnchecked = 0;
    /// GImpact mesh-mesh pairs whose contacts were computed ahead, on the narrow-phase threads
    /// (setNarrowPhaseThreads), and their search parts (a large pair's search is cut into several)
    std::size_t threadedMeshPairs = 0;
    std::size_t threadedTasks = 0;
    /// GImpact-convex pairs (convexPairs) whose triangles were collided ahead, on the narrow-phase threads, and their
    /// points then added in Bullet's order (from the second step with at least 64 of their triangles collided)
    std::size_t threadedConvexPairs = 0;
    /// Pairs whose broadphase boxes were farther apart than their contact breaking threshold: no algorithm call,
    /// their manifolds' points cleared (btDbvtBroadphase's fattened pairs that btAxisSweep3 would not hold)
    std::size_t apartPairs = 0;
    /// Pairs handed to the narrow-phase threads (setNarrowPhaseThreads) to run their Bullet algorithm: convex (GJK)
    /// pairs and convex against a BVH mesh or heightfield, while no application hook is installed and it pays
    std::size_t threadedPairs = 0;
    /// GImpact mesh vs static plane pairs (Bullet's vertex loop, most vertices ruled out by a cheaper bound first),
    /// the vertices of their parts whose box reached the plane (Bullet maps each), and of those the ones Bullet's
    /// test ran on
    std::size_t planePairs = 0;
    std::size_t planeVertices = 0;
    std::size_t planeVerticesTested = 0;
    double dispatchMs = 0.0;            ///< wall time in dispatchAllCollisionPairs
    void reset() { *this = CullideDispatchStats{}; }
};

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

    void setCullideBroadphase(CullideBroadphase* broadphase) { m_broadphase = broadphase; }
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
    friend struct detail::AdapterAccess;
    /// Used by the algorithms: counters for the current dispatch.
    CullideDispatchStats& currentStats() { return m_current; }
    /// Used by the GImpact algorithm: primitive -> leaf node of GImpact box sets (Bullet's candidate criterion).
    detail::GImpactLeafIndex& gimpactLeafIndex() { return *m_leafIndex; }
    /// Used by the GImpact algorithm: the mesh-mesh contacts computed on the narrow-phase threads during the current
    /// dispatch.
    detail::MeshContactBatch& meshContacts() { return *m_meshContacts; }
    /// The thread count in use (setNarrowPhaseThreads; 0 read as the machine's) and the pool of that many.
    unsigned narrowPhaseThreads() const;
    TaskPool& pool(unsigned threads);
    /// The kind of the pair's algorithm if it may run on a narrow-phase thread in this dispatch, else Other
    /// (src/ThreadedPairs.h).
    bullet::AlgorithmKind threadablePair(btBroadphasePair& pair);
    /// Lists the pair cache's GImpact mesh-mesh pairs that the dispatch will run through the GImpact algorithm, for
    /// the worker pool to compute their contacts while the dispatch runs; false when there are none.
    bool listMeshPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo);
    /// The dispatch loop over the broadphase's own pair cache (discrete dispatch, Bullet's near callback): pairs
    /// apart skipped, threadable pairs handed to the workers when `mayStream` (the pool is free) and it pays.
    void dispatchOwnPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                          btDispatcher* dispatcher, bool mayStream);

    CullideCollisionDispatcher(detail::PrecisionChecked, btCollisionConfiguration* collisionConfiguration,
                               CullideBroadphase* broadphase);

    CullideBroadphase* m_broadphase;
    CullideDispatchStats m_current;
    CullideDispatchStats m_lastStep;
    CullideDispatchStats m_total;
    std::unique_ptr<detail::GImpactLeafIndex> m_leafIndex;
    std::unique_ptr<detail::MeshContactBatch> m_meshContacts;
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
