// Which pairs of a dispatch may run Bullet's own algorithm on a narrow-phase thread, so that the dispatch gives what
// Bullet's single-threaded loop gives, bit for bit.
//
// In Bullet's dispatch loop, a pair's algorithm writes only to its own state and its own manifold, except where it
// - makes or frees a manifold or an algorithm (the dispatcher's pools and manifold list: the order in which
//   manifolds are made is the order the solver reads them in);
// - calls the application: the contact callbacks (gContactAddedCallback for objects flagged
//   CF_CUSTOM_MATERIAL_CALLBACK; gContactStarted/Ended/Processed/DestroyedCallback for every manifold), the friction
//   and restitution combiners (gCalculateCombined*Callback), a profile-zone hook, a debug drawer that draws, a near
//   callback of its own, its own shape or mesh-interface classes, its own algorithms;
// - writes a static table: btMinkowskiPenetrationDepthSolver (the configuration's solver when
//   m_useEpaPenetrationAlgorithm is off).
// A pair may therefore run on a worker when its algorithm is one of Bullet's classes that touch nothing else once
// they hold their manifold, on shapes of Bullet's own classes, and no application hook would be called:
// - btConvexConvexAlgorithm (GJK-EPA) once its manifold exists (it makes it on its first run);
// - btBoxBox, btSphereSphere, btSphereBox, btSphereTriangle and btConvexPlane algorithms (they make their manifold
//   when they are made);
// - btConvexConcaveCollisionAlgorithm against a btBvhTriangleMeshShape (over Bullet's btTriangleIndexVertexArray or
//   btTriangleMesh), its scaled form or a btHeightfieldTerrainShape, when the per-triangle algorithm is Bullet's
//   convex or sphere-triangle one: the algorithm it makes and frees per triangle comes from the heap on a worker
//   (CullideCollisionDispatcher::allocateCollisionAlgorithm), not from the pool;
// - btCompoundCollisionAlgorithm and btCompoundCompoundCollisionAlgorithm (btCompoundShapes of Bullet's convex
//   shapes, against a shape above or each other) when this run makes and frees no child algorithm
//   (compoundMayThread, compoundPairMayThread below) and every child algorithm it holds may run on a worker by these
//   rules.
// Everything else — algorithms made this step, compounds whose children start or stop overlapping the other shape,
// GImpact shapes, soft bodies, the adapter's own algorithms,
// every pair while an application hook is installed — runs on the calling thread, in the pair cache's order, so the
// manifolds are made in Bullet's order. Bullet's own multithreaded dispatcher (btCollisionDispatcherMt) runs these
// algorithms concurrently too; it is not used here because its manifold order depends on scheduling.
// Left to the application: a custom btAlignedAlloc (btAlignedAllocSetCustom) must be thread-safe, as Bullet's own
// multithreading requires; a Bullet built with its profiler (BT_ENABLE_PROFILE) counts its threads unsafely.
#pragma once

#include "narrowphase/Waiter.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>

#include <atomic>
#include <cstddef>
#include <functional>
#include <typeinfo>
#include <vector>

class btCollisionShape;
class btCollisionObject;
struct btCollisionAlgorithmCreateFunc;

namespace cullide::bullet {

/// A pair's algorithm, by its exact class: Bullet's own only (subclasses and the application's classes are Other).
enum class AlgorithmKind : int {
    Other,          ///< runs on the calling thread
    Convex,         ///< btBoxBox, btSphereSphere, btSphereBox, btSphereTriangle, btConvexPlane collision algorithms
    ConvexConvex,   ///< btConvexConvexAlgorithm: makes its manifold on its first run
    ConvexConcave,  ///< btConvexConcaveCollisionAlgorithm: makes and frees an algorithm per triangle
    Compound,       ///< btCompound(Compound)CollisionAlgorithm: makes and frees its children's algorithms
};
AlgorithmKind algorithmKindOf(const std::type_info& algorithmClass);

/// Whether running `algorithm` on a pair whose boxes are apart would make or free no manifold, so that skipping it
/// (ApartPairs.h) leaves the dispatcher's manifolds as Bullet's: Bullet's convex, convex-convex and convex-mesh
/// algorithms keep their manifold for their lifetime; a compound algorithm frees the algorithms (and manifolds) of
/// the children whose boxes no longer overlap the other shape's, so it qualifies only while it holds none. Any
/// other algorithm (the application's own, Bullet's for other shapes) may do anything: false.
bool freesNoManifoldWhenApart(const btCollisionAlgorithm& algorithm);

/// Whether handing a threadable pair of this kind to another thread pays: GJK and convex-mesh pairs do (~1-5 us on
/// the 2-core machine); the closed-form convex algorithms (box-box ~0.2 us a pair) cost about what the hand-off costs
/// (the pair's data then misses the other core's cache), so they stay on the calling thread.
bool worthHandingOff(AlgorithmKind kind);

/// A pair's typical narrow-phase cost, in units of a box-box pair (~0.2 us on the 2-core machine; measured on the
/// swap bench's scenes): hull pairs ~4, convex against a mesh ~16. Used to decide whether waking workers pays.
std::size_t typicalCost(AlgorithmKind kind);

/// Whether an algorithm of `kind` on these shapes (either order) may run on a narrow-phase thread. `pairFunc`: the
/// dispatcher's creation function for the two shape types (ConvexConvex: Bullet's, with GJK-EPA); `triangleFunc`:
/// its creation function for the convex shape against TRIANGLE_SHAPE_PROXYTYPE (ConvexConcave: Bullet's convex
/// one with GJK-EPA, or the sphere-triangle one). The caller checks that a ConvexConvex algorithm holds its manifold.
bool threadableAlgorithm(AlgorithmKind kind, const btCollisionShape& shape0, const btCollisionShape& shape1,
                         const btCollisionAlgorithmCreateFunc* pairFunc,
                         const btCollisionAlgorithmCreateFunc* triangleFunc);

/// Whether the dispatcher's algorithm for a triangle and `convex` (`triangleFunc`, the creation function for the two
/// in the order they are collided) may run on a narrow-phase thread: `convex` one of Bullet's convex shapes, the
/// algorithm Bullet's convex one with GJK-EPA or Bullet's sphere-triangle one (which read their manifold only for its
/// thresholds and its point count).
bool convexTriangleThreadable(const btCollisionShape& convex, const btCollisionAlgorithmCreateFunc* triangleFunc);

/// The dispatcher's creation functions for contact-point queries by the two shape types (btCollisionDispatcher's
/// m_doubleDispatchContactPoints, which only the dispatcher reads).
using CreateFuncTable =
    btCollisionAlgorithmCreateFunc* [MAX_BROADPHASE_COLLISION_TYPES][MAX_BROADPHASE_COLLISION_TYPES];

/// The kind of the pair's existing algorithm if its next run, as Bullet's near callback runs it in a discrete
/// dispatch, may happen on a narrow-phase thread, else Other: threadableAlgorithm's rules for the algorithm on the
/// objects' shapes, a ConvexConvex algorithm that holds its manifold (Convex where btConvexConvexAlgorithm collides
/// the pair in closed form: capsule-capsule, capsule-sphere), and for a compound (compoundMayThread) the same
/// rules for each child algorithm on the child's shape. The caller checks the objects (objectsMayThread,
/// needsCollision) and the dispatch (dispatchMayThread). `scratch` is reused between calls.
AlgorithmKind threadableKind(btCollisionAlgorithm& algorithm, const btCollisionObject& object0,
                             const btCollisionObject& object1, const CreateFuncTable& funcs,
                             btManifoldArray& scratch);

/// Whether a child algorithm of a compound may run on a worker (threadableKind's rules, the child's shape as the
/// algorithm's first shape and the other object's shape, or the other compound's child, as its second).
using ChildThreadable = std::function<bool(btCollisionAlgorithm& child, const btCollisionShape& childShape,
                                           const btCollisionShape& otherShape)>;

/// Whether a btCompoundCollisionAlgorithm's next run on these objects may happen on a worker: one of its child
/// algorithms is worth handing off (worthHandingOff: compounds of boxes on boxes stay, as box pairs do), and the run
/// makes or frees no child algorithm, so that it touches only what it holds. Bullet's algorithm (discrete dispatch:
/// no closest-point distance) makes a child's algorithm when the child's world box, as it computes it, overlaps the
/// other shape's world box and frees it when they no longer overlap; it remakes all of them when the compound's
/// revision changed. So: the same revision, at most 16 children, all Bullet convex shapes, and each child holding an
/// algorithm exactly when its box overlaps the other's — where an overlap is within a few ulps of the coordinates of
/// being decided the other way (a box rounded differently than in Bullet's build), the pair stays on the calling
/// thread.
bool compoundMayThread(btCollisionAlgorithm& algorithm, const btCollisionObject& object0,
                       const btCollisionObject& object1, const ChildThreadable& childThreadable);

/// The same for a btCompoundCompoundCollisionAlgorithm (two compounds, each with its box tree; a child pair's
/// algorithm worth handing off): it makes a child pair's algorithm when the two children's world boxes overlap (and
/// its trees find them) and frees it when they no longer do, and frees all when either revision changed. So: the
/// same revisions, at most 16 children each, all Bullet convex shapes, and its cache of child pairs holding exactly
/// the clearly overlapping ones.
bool compoundPairMayThread(btCollisionAlgorithm& algorithm, const btCollisionObject& object0,
                           const btCollisionObject& object1, const ChildThreadable& childThreadable);

/// Whether nothing installed process-wide forbids workers in this dispatch: discrete dispatch, none of Bullet's
/// manifold callbacks, Bullet's friction/restitution combiners and profile hooks, no debug drawer that draws.
bool dispatchMayThread(const btDispatcherInfo& info);

/// Whether the objects may be collided on a worker: rigid bodies or plain collision objects, and not a pair that
/// calls gContactAddedCallback (an object flagged CF_CUSTOM_MATERIAL_CALLBACK while the callback is set).
bool objectsMayThread(const btCollisionObject& object0, const btCollisionObject& object1);

/// Runs the pair's algorithm as Bullet's near callback does in a discrete dispatch, for a pair whose algorithm
/// exists and whose objects need collision (the caller has checked both).
void collidePair(btBroadphasePair& pair, const btDispatcherInfo& info);

/// The pairs the calling thread hands to the narrow-phase threads while it goes through the pair cache: one producer
/// (push, then close), any number of consumers (consume) running at the same time. Storage is reserved up front, so
/// consumers read pairs while more are pushed.
class PairStream {
public:
    /// Empties the stream and makes room for `capacity` pairs.
    void reset(std::size_t capacity);
    /// Publishes a pair; false (nothing published) when the reserved room is full.
    bool push(btBroadphasePair* pair);
    /// No more pairs: consumers return once the published ones are taken.
    void close();
    /// Collides published pairs (collidePair) until the stream is closed and none is left.
    void consume(const btDispatcherInfo& info);
    std::size_t size() const { return m_published.load(std::memory_order_relaxed); }

private:
    std::vector<btBroadphasePair*> m_pairs;
    std::atomic<std::size_t> m_published{0};
    std::atomic<std::size_t> m_next{0};
    std::atomic<bool> m_closed{false};
    Waiter m_waiter;  // consumers ahead of the producer sleep here
};

/// Marks the current thread, while it lives, as running pairs of a threaded dispatch: algorithms made on it come from
/// the heap instead of the dispatcher's pool (onPairThread()).
class PairThreadScope {
public:
    PairThreadScope();
    ~PairThreadScope();
    PairThreadScope(const PairThreadScope&) = delete;
    PairThreadScope& operator=(const PairThreadScope&) = delete;

private:
    bool m_outer;
};
bool onPairThread();

}  // namespace cullide::bullet
