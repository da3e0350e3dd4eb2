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
//   (CullideCollisionDispatcher::allocateCollisionAlgorithm), not from the pool.
// Everything else — algorithms made this step, compounds, GImpact shapes, soft bodies, the adapter's own algorithms,
// every pair while an application hook is installed — runs on the calling thread, in the pair cache's order, so the
// manifolds are made in Bullet's order. Bullet's own multithreaded dispatcher (btCollisionDispatcherMt) runs these
// algorithms concurrently too; it is not used here because its manifold order depends on scheduling.
// Left to the application: a custom btAlignedAlloc (btAlignedAllocSetCustom) must be thread-safe, as Bullet's own
// multithreading requires; a Bullet built with its profiler (BT_ENABLE_PROFILE) counts its threads unsafely.
#pragma once

#include "Waiter.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/BroadphaseCollision/btDispatcher.h>

#include <atomic>
#include <cstddef>
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
};
AlgorithmKind algorithmKindOf(const std::type_info& algorithmClass);

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
