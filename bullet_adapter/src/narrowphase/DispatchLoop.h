// Bullet's dispatch loop over a pair cache (btCollisionDispatcher's: the near callback for every pair, in the cache's
// order), except for pairs provably apart (ApartPairs.h): their algorithm is not called and their manifolds get
// what it would give them. Given a test for the pairs that may run on the narrow-phase threads (ThreadedPairs.h) and
// a stream, it hands those pairs to the stream (the worker pool collides them meanwhile) and runs the others itself,
// in the cache's order, so that manifolds and algorithms are made and freed in Bullet's order. Without a stream it
// runs every pair itself.
#pragma once

#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>

#include <cstddef>
#include <functional>

namespace cullide::bullet {

class DispatchLoop final : public btOverlapCallback {
public:
    /// The kind of a pair's algorithm if it may run on a narrow-phase thread, else AlgorithmKind::Other.
    using Threadable = std::function<AlgorithmKind(btBroadphasePair&)>;

    DispatchLoop(btCollisionDispatcher& dispatcher, const btDispatcherInfo& info, const Threadable* threadable,
                 PairStream* stream)
        : m_dispatcher(dispatcher), m_info(info), m_threadable(threadable), m_stream(stream) {}

    bool processOverlap(btBroadphasePair& pair) override;

    std::size_t skipped = 0;         ///< pairs apart: algorithm not called
    std::size_t threadableCost = 0;  ///< typicalCost of the pairs that could run on the threads

private:
    btCollisionDispatcher& m_dispatcher;
    const btDispatcherInfo& m_info;
    const Threadable* m_threadable;
    PairStream* m_stream;
    btManifoldArray m_scratch;
};

/// Marks the worker pool as serving the dispatch under way, until the scope ends (also on an exception): a dispatch
/// nested in a pair's algorithm (rare) then runs without the pool.
class PoolClaim {
public:
    explicit PoolClaim(bool& busy) : m_busy(busy) { m_busy = true; }
    ~PoolClaim() { m_busy = false; }
    PoolClaim(const PoolClaim&) = delete;
    PoolClaim& operator=(const PoolClaim&) = delete;

private:
    bool& m_busy;
};

/// Closes a stream when the producer is done, also when it throws (the consumers would wait for more).
struct CloseWhenDone {
    PairStream& stream;
    ~CloseWhenDone() { stream.close(); }
};

}  // namespace cullide::bullet
