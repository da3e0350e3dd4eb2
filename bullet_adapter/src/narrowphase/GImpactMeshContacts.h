// Bullet's contacts of GImpact mesh-mesh pairs (btGImpactCollisionAlgorithm's gimpact_vs_gimpact for two
// btGImpactMeshShapes: per part pair, the box-set pair search, then collide_sat_triangles), computed as values:
// the points in the order Bullet adds them to the manifold, with the shape identifiers it sets for each. The
// dispatcher's algorithm then adds them to the manifold itself, so the manifold is Bullet's bit for bit.
//
// Computing them touches nothing but the shapes' data (read-only, the parts locked by the caller), per-thread
// scratch and the dispatch's shared prepared triangles (TriangleStore, filled first come first served): no manifold,
// no callback, no allocator of Bullet's. So many pairs, and the parts of one large pair's
// descent, run on worker threads (MeshContactBatch) while the manifolds are still made on the calling thread, in
// Bullet's dispatch order. The batch also computes GImpact-convex pairs ahead (GImpactConvexContacts.h: Bullet's
// per-triangle algorithms into a manifold of their own).
#pragma once

#include "narrowphase/GImpactLeafPairs.h"
#include "narrowphase/Waiter.h"

#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/Gimpact/btTriangleShapeEx.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

class btCollisionDispatcher;
class btCollisionObject;
struct btDispatcherInfo;

namespace cullide {
class TaskPool;
namespace bullet {

/// One point as collide_sat_triangles hands it to btGImpactCollisionAlgorithm::addContactPoint, with the part and
/// triangle of each side that Bullet sets as the result's shape identifiers.
struct MeshContact {
    btVector3 point;
    btVector3 normal;
    btScalar distance;
    int part0, face0, part1, face1;
};

/// Candidate triangles of one GImpact-convex loop: Bullet's query found, collided, collided without the reach test.
struct ConvexCounts {
    std::size_t candidates = 0, triangles = 0, unchecked = 0;
};

/// A world-space triangle as Bullet's collide_sat_triangles prepares it (btPrimitiveTriangle: vertices mapped by the
/// body's transform, plane built), with the three edge planes its clip method builds for every pair it tests, built
/// here once (the same calls on the same values: the same planes).
struct PreparedTriangle {
    btPrimitiveTriangle triangle;
    btVector4 edges[3];
};

/// btPrimitiveTriangle::overlap_test_conservative (which Bullet declares non-const): false when either triangle lies
/// entirely beyond the other's plane by more than both margins.
bool planesMayMeet(const btPrimitiveTriangle& a, const btPrimitiveTriangle& b);

/// btPrimitiveTriangle::find_triangle_collision_clip_method on prepared triangles: each triangle clipped by the
/// other's edge planes (Bullet's bt_plane_clip_triangle / bt_plane_clip_polygon), the points merged against its plane
/// (GIM_TRIANGLE_CONTACT::merge_points), the deeper side kept — Bullet's steps in Bullet's order, so the same contact
/// bit for bit. A pair whose second side would surely be clipped away (no contact from Bullet either) returns false
/// before the first side is clipped.
bool clipMethodContact(const PreparedTriangle& a, const PreparedTriangle& b, GIM_TRIANGLE_CONTACT& contact);

/// A GImpact part's triangles under one transform as PreparedTriangles, each prepared by the first thread that asks
/// for it within one begin() .. begin() span and then shared by every thread. The part must stay locked meanwhile.
class TriangleStore {
public:
    TriangleStore() = default;
    TriangleStore(const TriangleStore&) = delete;
    TriangleStore& operator=(const TriangleStore&) = delete;

    /// Starts a span for `part` under `t` (copied): no triangle is prepared. Not concurrent with get().
    void begin(const btGImpactMeshShapePart& part, const btTransform& t);
    /// Triangle `prim` in world space, or nullptr when the part has no such primitive. Any number of threads at once:
    /// while another thread prepares the store's copy, the triangle is prepared into `spare` and that is returned.
    const PreparedTriangle* get(int prim, PreparedTriangle& spare);
    /// Triangles the store has room for (its memory, kept between spans).
    std::size_t capacity() const { return m_capacity; }
    const btTransform& transform() const { return m_transform; }
    /// Hints that triangle `prim` will be asked for soon: its slot, its stamp and its indices (prefetchSlot), then,
    /// once those have arrived and unless it is prepared, its vertices (prefetchVertices). No effect on results. The
    /// part must be locked.
    void prefetchSlot(int prim) const;
    void prefetchVertices(int prim) const;

private:
    void prepare(int prim, PreparedTriangle& out) const;

    const btGImpactMeshShapePart* m_part = nullptr;
    const btGImpactMeshShapePart::TrimeshPrimitiveManager* m_mesh = nullptr;  // the part's mesh data
    btTransform m_transform;
    /// Frees the slots' storage (allocated for PreparedTriangle's alignment).
    struct FreeSlots {
        void operator()(PreparedTriangle* slots) const;
    };
    /// Raw storage, not written when allocated: a slot holds a triangle once prepared in the span. A large store's
    /// pages are then first touched by the threads that prepare their triangles, and only where triangles are asked
    /// for (writing all of it up front cost ~1 ms per 20K triangles, serial, on the dispatch's first step).
    std::unique_ptr<PreparedTriangle, FreeSlots> m_triangles;
    std::unique_ptr<std::atomic<std::uint32_t>[]> m_stamp;  // m_epoch: prepared; m_epoch | kBusy: being prepared
    std::size_t m_capacity = 0;
    std::size_t m_count = 0;
    std::uint32_t m_epoch = 0;
};

/// Working memory of one thread's contact computations.
struct MeshContactScratch {
    LeafPairScratch leaves;
    TriangleStore world0, world1;
    std::vector<int> interleaved;
};

/// This thread's scratch (worker threads and the dispatching thread alike).
MeshContactScratch& threadScratch();

/// A pair's points as lists held elsewhere (the batch's per-task lists, or one list of the caller's), read in place:
/// the lists in order, each list's points in order.
class ContactLists {
public:
    ContactLists() = default;
    ContactLists(const std::vector<MeshContact>* first, std::size_t count) : m_first(first), m_count(count) {}
    template <typename Visit>
    void forEach(const Visit& visit) const {
        for (std::size_t l = 0; l < m_count; ++l)
            for (const MeshContact& c : m_first[l]) visit(c);
    }
    /// The points, counted.
    std::size_t size() const;

private:
    const std::vector<MeshContact>* m_first = nullptr;
    std::size_t m_count = 0;
};

/// One part pair of a mesh pair: its indices and world transforms (as the algorithm's wrappers give them).
struct PartPair {
    const btGImpactMeshShapePart* part0;
    const btGImpactMeshShapePart* part1;
    int index0, index1;
    const btTransform* trans0;
    const btTransform* trans1;
};

/// Bullet's triangle routine (the conservative plane test, then the clip method) over the triangle pairs
/// `interleaved` (prim0, prim1, ...) of one part pair, in that order; the points appended to `out`. Both parts
/// locked; world0 / world1 begun for these parts and transforms by the caller.
void triangleContacts(const PartPair& parts, const std::vector<int>& interleaved, TriangleStore& world0,
                      TriangleStore& world1, std::vector<MeshContact>& out);

/// Bullet's whole mesh-mesh contact search for two btGImpactMeshShapes whose parts all have box sets: part pairs
/// in Bullet's order (part 0 descending, then part 1 descending), Bullet's box-set pairs of each in Bullet's order,
/// Bullet's triangle routine on each. Locks and unlocks the parts itself.
void meshPairContacts(const btGImpactMeshShape& shape0, const btTransform& trans0, const btGImpactMeshShape& shape1,
                      const btTransform& trans1, MeshContactScratch& scratch, std::vector<MeshContact>& out);

/// The mesh-mesh pairs of one dispatch, their contacts computed on a worker pool while the dispatch runs. A large
/// pair's search is split into parts (LeafPairSearch::split) so that even one pair keeps every worker busy; each
/// part's points go to its own list, and a pair's points are its parts' lists in order: the same points in the same
/// order as meshPairContacts, whatever the thread count or scheduling. The workers take the tasks in the pairs'
/// order; the dispatching thread meanwhile goes through the pair cache, and a pair's algorithm asks for its points
/// (find), running pending tasks itself until its own are done: the manifolds are still made on the calling thread,
/// in Bullet's dispatch order, while the workers compute the pairs after it.
class MeshContactBatch {
public:
    MeshContactBatch() = default;
    MeshContactBatch(const MeshContactBatch&) = delete;
    MeshContactBatch& operator=(const MeshContactBatch&) = delete;

    /// Forgets the previous dispatch's pairs (keeps the memory).
    void clear();
    /// A pair the dispatch will process with the objects in this order; both shapes are btGImpactMeshShapes whose
    /// parts all have box sets. The transforms are copied.
    void add(const btCollisionObject* object0, const btCollisionObject* object1, const btGImpactMeshShape& shape0,
             const btGImpactMeshShape& shape1, const btTransform& trans0, const btTransform& trans1);
    /// A GImpact-convex pair the dispatch will process with the objects in this order (its pieces computed by
    /// bullet::convexChunkContacts): one shape a btGImpactMeshShape whose parts all have box sets, the other a convex
    /// shape whose algorithm with a triangle may run on a worker (bullet::convexTriangleThreadable,
    /// bullet::pointsIndependentOfManifold). `dispatcher` and `info` are the dispatch's, the same for every pair.
    void addConvex(const btCollisionObject* object0, const btCollisionObject* object1, const btCollisionShape& shape0,
                   const btCollisionShape& shape1, const btTransform& trans0, const btTransform& trans1,
                   btCollisionDispatcher& dispatcher, const btDispatcherInfo& info);
    /// The pairs added with addConvex.
    std::size_t convexCount() const { return m_convexCount; }
    std::size_t size() const { return m_pairCount; }
    /// Computes the pairs' points on `pool`'s workers (nullptr: none) while this thread runs `meanwhile` (the
    /// dispatch, whose algorithms call find); then the tasks nobody took. The parts are locked on this thread for
    /// the duration. A task that fails (out of memory) leaves its pair to its algorithm; an exception from
    /// `meanwhile` is rethrown once the workers are done.
    void run(TaskPool* pool, const std::function<void()>& meanwhile);
    /// During run(), on the thread that called it: the points of (object0, object1) when the batch computes them for
    /// exactly these shapes and transforms, once its tasks are done (running pending tasks meanwhile), read in place
    /// from the tasks' lists (valid until the batch runs or is cleared again); nullptr otherwise (the caller computes
    /// them itself).
    const ContactLists* find(const btCollisionObject* object0, const btCollisionObject* object1,
                             const btCollisionShape* shape0, const btCollisionShape* shape1, const btTransform& trans0,
                             const btTransform& trans1);
    /// A GImpact-convex pair's points computed ahead, with what its loop counted and whether it makes the manifold.
    struct ConvexAhead {
        ContactLists contacts;
        ConvexCounts counts;
        bool manifold = false;
        /// The breaking threshold the triangles' algorithms were given (btCollisionDispatcher::getNewManifold's for
        /// the pair): the points are the pair's when its manifold has the same.
        btScalar breakingThreshold = 0;
    };
    /// find for a pair added with addConvex, dispatched with the batch's dispatch info.
    const ConvexAhead* findConvex(const btCollisionObject* object0, const btCollisionObject* object1,
                                  const btCollisionShape* shape0, const btCollisionShape* shape1,
                                  const btTransform& trans0, const btTransform& trans1, const btDispatcherInfo& info);

    /// Search parts (tasks) of the last run.
    std::size_t taskCount() const { return m_tasks.size(); }
    /// Shared triangle stores of the last run (one per part and transform of a pair cut into parts, within budget).
    std::size_t sharedStores() const { return m_storeCount; }
    /// What the shared stores may hold, in bytes (kSharedTriangleBytes unless set; a test sets it lower).
    void setSharedTriangleBudget(std::size_t bytes) { m_storeBudget = bytes; }

private:
    struct Pair {
        const btCollisionObject* object0;
        const btCollisionObject* object1;
        const btCollisionShape* shape0;  // btGImpactMeshShapes, or (convex) one of them and a convex shape
        const btCollisionShape* shape1;
        btTransform trans0, trans1;
        std::size_t firstTask, endTask;
        bool convex;
        bool convexFirst;  // convex pair: the convex shape is shape0
        ConvexAhead ahead;  // the tasks' lists, once Ready; for a convex pair, its counts and manifold too
        enum class Points { Pending, Ready, Failed } points;
    };
    struct Task {
        std::size_t pair;
        std::size_t search;  ///< mesh pair: its part pair's search; convex pair: its part's candidates (m_candidates)
        int part0, part1;    ///< convex pair: part0 the mesh's part
        NodePair start;
        std::size_t store0, store1;  ///< the parts' shared triangles (m_stores), or kNoStore
        int first = 0, count = 0;    ///< convex pair: the candidates [first, first + count) of its part
    };
    struct PairKeyHash {
        std::size_t operator()(const std::pair<const btCollisionObject*, const btCollisionObject*>& k) const {
            return std::hash<const void*>()(k.first) * 31u ^ std::hash<const void*>()(k.second);
        }
    };

    Pair& addPair(const btCollisionObject* object0, const btCollisionObject* object1, const btCollisionShape& shape0,
                  const btCollisionShape& shape1, const btTransform& trans0, const btTransform& trans1);
    /// The pair of (object0, object1) for these shapes and transforms, its points computed (waiting for its tasks),
    /// or nullptr.
    Pair* computed(const btCollisionObject* object0, const btCollisionObject* object1, const btCollisionShape* shape0,
                   const btCollisionShape* shape1, const btTransform& trans0, const btTransform& trans1);
    void makeTasks(std::size_t target, MeshContactScratch& scratch);
    /// A convex pair's tasks: per mesh part (last to first), its candidates in pieces of kConvexChunk, the last
    /// piece first (the loop's order).
    void makeConvexTasks(std::size_t pair);
    /// Candidates per task of a convex pair: a piece runs ~50 GJK queries (~30 us), the pair's share of the workers.
    static constexpr int kConvexChunk = 48;
    /// The store of `part`'s triangles under `t` for this dispatch (one per part and transform, shared by its
    /// tasks), or kNoStore when a new one would take the stores beyond kSharedTriangleBytes.
    std::size_t storeFor(const btGImpactMeshShapePart& part, const btTransform& t);
    static constexpr std::size_t kNoStore = ~std::size_t{0};
    /// What the shared stores may hold (~230K prepared triangles); tasks of parts beyond it prepare their own.
    static constexpr std::size_t kSharedTriangleBytes = std::size_t{32} << 20;
    void runTask(std::size_t task, MeshContactScratch& scratch);
    /// Takes the next task nobody took and runs it; false when none is left.
    bool runNextTask();
    /// Makes the tasks for `target` parts per large pair and readies their states (none, each pair Failed, when out
    /// of memory).
    void prepareTasks(std::size_t target);
    /// Whether every task of the pair succeeded, waiting for (and meanwhile running) tasks until they are done.
    bool waitForTasks(const Pair& pair);
    void lockParts(bool lock) const;

    std::vector<Pair> m_pairs;  // the first m_pairCount are this dispatch's
    std::size_t m_pairCount = 0;
    std::size_t m_convexCount = 0;
    btCollisionDispatcher* m_dispatcher = nullptr;  // the convex pairs' dispatch
    const btDispatcherInfo* m_info = nullptr;
    std::vector<LeafPairSearch> m_searches;
    std::vector<Task> m_tasks;
    std::vector<std::vector<MeshContact>> m_taskContacts;
    std::vector<ConvexCounts> m_taskCounts;                  // convex tasks' counts
    std::vector<btAlignedObjectArray<int>> m_candidates;     // convex pairs' parts' candidates (m_candidateCount)
    std::size_t m_candidateCount = 0;
    std::vector<NodePair> m_split;
    std::vector<std::unique_ptr<TriangleStore>> m_stores;  // the first m_storeCount are this dispatch's
    std::size_t m_storeCount = 0;
    std::size_t m_storeTriangles = 0;  // the stores' capacities, summed
    std::size_t m_storeBudget = kSharedTriangleBytes;
    std::unordered_map<const btGImpactMeshShapePart*, std::vector<std::size_t>> m_storeIndex;
    std::unordered_map<std::pair<const btCollisionObject*, const btCollisionObject*>, std::size_t, PairKeyHash>
        m_index;
    /// Per task: 0 pending, 1 done, 2 failed (out of memory).
    std::unique_ptr<std::atomic<int>[]> m_taskState;
    std::size_t m_taskStateSize = 0;
    std::atomic<std::size_t> m_nextTask{0};
    bullet::Waiter m_taskDone;  // the dispatching thread waits here for a worker's task
    std::atomic<bool> m_tasksMade{false};
    bullet::Waiter m_tasksReady;  // the workers wait here while the dispatching thread makes the tasks
    bool m_running = false;
};

}  // namespace bullet
}  // namespace cullide
