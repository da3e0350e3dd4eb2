#include "cullide_bullet/CullideCollisionDispatcher.h"

#include "broadphase/PairRecords.h"
#include "cullide/TaskPool.h"
#include "cullide/Timer.h"
#include "narrowphase/AheadPairs.h"
#include "narrowphase/AlgorithmTable.h"
#include "narrowphase/DispatchLoop.h"
#include "narrowphase/NarrowPhaseContext.h"
#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <LinearMath/btPoolAllocator.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <thread>

namespace cullide {

namespace {

/// The default narrow-phase thread count: the machine's hardware threads, at most 8. Read once per process:
/// std::thread::hardware_concurrency reads /sys/devices/system/cpu/online (three system calls, ~8 us), which every
/// dispatch paid before (the whole narrow phase of a 55-box stack is ~25 us).
unsigned machineThreads() {
    static const unsigned threads = std::min(8u, std::max(1u, std::thread::hardware_concurrency()));
    return threads;
}

}  // namespace

CullideCollisionDispatcher::CullideCollisionDispatcher(detail::PrecisionChecked,
                                                       btCollisionConfiguration* collisionConfiguration,
                                                       CullideBroadphase* broadphase)
    : btCollisionDispatcher(collisionConfiguration),
      m_broadphase(nullptr),
      m_context(std::make_unique<bullet::NarrowPhaseContext>()),
      m_algorithms(std::make_unique<bullet::AlgorithmTable>(*m_context)) {
    setCullideBroadphase(broadphase);
}

CullideCollisionDispatcher::~CullideCollisionDispatcher() = default;

void CullideCollisionDispatcher::setCullideBroadphase(CullideBroadphase* broadphase) {
    m_broadphase = broadphase;
    m_context->records = broadphase != nullptr ? &bullet::pairRecordsOf(*broadphase) : nullptr;
}

void CullideCollisionDispatcher::setNarrowPhaseThreads(unsigned threads) {
    if (threads > kMaxNarrowPhaseThreads)
        throw std::invalid_argument("CullideCollisionDispatcher::setNarrowPhaseThreads: " + std::to_string(threads) +
                                    " threads requested, at most " + std::to_string(kMaxNarrowPhaseThreads));
    if (threads == m_threads) return;
    m_threads = threads;
    m_pool.reset();
}

unsigned CullideCollisionDispatcher::narrowPhaseThreads() const {
    return m_threads != 0 ? m_threads : machineThreads();
}

TaskPool& CullideCollisionDispatcher::pool(unsigned threads) {
    if (!m_pool || m_pool->size() != threads) m_pool = std::make_unique<TaskPool>(threads);
    return *m_pool;
}

btCollisionAlgorithm* CullideCollisionDispatcher::findAlgorithm(const btCollisionObjectWrapper* body0Wrap,
                                                                const btCollisionObjectWrapper* body1Wrap,
                                                                btPersistentManifold* sharedManifold,
                                                                ebtDispatcherQueryType queryType) {
    if (queryType == BT_CONTACT_POINT_ALGORITHMS && m_broadphase != nullptr) {
        const btCollisionAlgorithmCreateFunc* registered =
            m_doubleDispatchContactPoints[body0Wrap->getCollisionShape()->getShapeType()]
                                         [body1Wrap->getCollisionShape()->getShapeType()];
        if (btCollisionAlgorithmCreateFunc* replacement = m_algorithms->replacementFor(
                body0Wrap, body1Wrap, registered, *m_broadphase)) {
            btCollisionAlgorithmConstructionInfo ci;
            ci.m_dispatcher1 = this;
            ci.m_manifold = sharedManifold;
            return replacement->CreateCollisionAlgorithm(ci, body0Wrap, body1Wrap);
        }
    }
    return btCollisionDispatcher::findAlgorithm(body0Wrap, body1Wrap, sharedManifold, queryType);
}

bullet::AlgorithmKind CullideCollisionDispatcher::threadablePair(btBroadphasePair& pair) {
    // An algorithm not made yet is made by this dispatch, on the calling thread, in Bullet's order.
    if (pair.m_algorithm == nullptr) return bullet::AlgorithmKind::Other;
    const auto* object0 = static_cast<const btCollisionObject*>(pair.m_pProxy0->m_clientObject);
    const auto* object1 = static_cast<const btCollisionObject*>(pair.m_pProxy1->m_clientObject);
    if (!bullet::objectsMayThread(*object0, *object1) || !needsCollision(object0, object1))
        return bullet::AlgorithmKind::Other;
    return bullet::threadableKind(*pair.m_algorithm, *object0, *object1, m_doubleDispatchContactPoints,
                                  m_manifoldScratch);
}

bool CullideCollisionDispatcher::listAheadPairs(btOverlappingPairCache* pairCache,
                                                const btDispatcherInfo& dispatchInfo) {
    bullet::AheadInputs in{*this, m_doubleDispatchContactPoints};
    in.threads = narrowPhaseThreads();
    in.gimpactPairCulling = m_broadphase != nullptr && m_broadphase->getGImpactPairCulling();
    in.gimpactConvexCulling = m_broadphase != nullptr && m_broadphase->getGImpactConvexCulling();
    in.lastConvexTriangles = m_lastStep.convexTriangles;
    return bullet::listAheadPairs(*pairCache, dispatchInfo, in, *m_context);
}

void CullideCollisionDispatcher::dispatchOwnPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                                                  btDispatcher* dispatcher, bool mayStream) {
    using bullet::DispatchLoop;
    CullideDispatchStats& stats = m_context->stats;
    const unsigned threads = narrowPhaseThreads();
    const DispatchLoop::Threadable threadable = [this](btBroadphasePair& pair) { return threadablePair(pair); };
    // Pairs are sorted into threadable and not (~15 ns a pair) while threads might pay: a scene whose last
    // count was far below kMinThreadedCost is counted again every kRecountDispatches dispatches only.
    const bool mayThread = threads > 1 && bullet::dispatchMayThread(dispatchInfo) &&
                           (4 * m_lastThreadableCost >= kMinThreadedCost ||
                            ++m_dispatchesSinceCount >= kRecountDispatches);
    if (mayThread) m_dispatchesSinceCount = 0;
    // The workers are woken when the previous dispatch's threadable pairs were worth it: below kMinThreadedCost
    // (bullet::typicalCost units, ~60 us of work) waking one (~25 us here) costs more than it saves.
    if (mayStream && !m_poolBusy && mayThread && m_lastThreadableCost >= kMinThreadedCost) {
        const bullet::PoolClaim claim{m_poolBusy};
        bullet::PairStream stream;
        stream.reset(static_cast<std::size_t>(pairCache->getNumOverlappingPairs()));
        DispatchLoop loop(*this, dispatchInfo, &threadable, &stream);
        const auto produce = [&] {
            const bullet::CloseWhenDone closer{stream};
            pairCache->processAllOverlappingPairs(&loop, dispatcher, dispatchInfo);
        };
        const auto consume = [&](std::size_t, std::size_t) { stream.consume(dispatchInfo); };
        pool(threads).parallelFor(threads, 1, consume, produce);
        stats.apartPairs = loop.skipped;
        stats.threadedPairs = stream.size();
        m_lastThreadableCost = loop.threadableCost;
    } else {
        DispatchLoop loop(*this, dispatchInfo, mayThread ? &threadable : nullptr, nullptr);
        pairCache->processAllOverlappingPairs(&loop, dispatcher, dispatchInfo);
        stats.apartPairs = loop.skipped;
        if (mayThread) m_lastThreadableCost = loop.threadableCost;
    }
}

void CullideCollisionDispatcher::dispatchAllCollisionPairs(btOverlappingPairCache* pairCache,
                                                           const btDispatcherInfo& dispatchInfo,
                                                           btDispatcher* dispatcher) {
    CullideDispatchStats& stats = m_context->stats;
    const CullideDispatchStats outer = stats;  // nested dispatches (rare) keep the outer counters
    stats.reset();
    const bool ownCache = m_broadphase != nullptr && pairCache == m_broadphase->getOverlappingPairCache();
    if (ownCache) m_context->leafIndex.beginDispatch();  // once per step, not for a character controller's cache
    cullide::Timer watch;
    const auto dispatchPairs = [&](bool mayStream) {
        if (ownCache && dispatchInfo.m_dispatchFunc == btDispatcherInfo::DISPATCH_DISCRETE &&
            getNearCallback() == &btCollisionDispatcher::defaultNearCallback)
            dispatchOwnPairs(pairCache, dispatchInfo, dispatcher, mayStream);
        else
            btCollisionDispatcher::dispatchAllCollisionPairs(pairCache, dispatchInfo, dispatcher);
    };
    // GImpact mesh-mesh (and GImpact-convex) pairs: the workers compute their contacts while this thread dispatches.
    if (!m_poolBusy && listAheadPairs(pairCache, dispatchInfo)) {
        const bullet::PoolClaim claim{m_poolBusy};  // a nested dispatch leaves the batch and pool alone
        bullet::MeshContactBatch& batch = m_context->meshContacts;
        batch.run(&pool(narrowPhaseThreads()), [&] { dispatchPairs(false); });
        stats.threadedMeshPairs = batch.size() - batch.convexCount();
        stats.threadedTasks = batch.taskCount();
        batch.clear();
    } else {
        dispatchPairs(true);
    }
    finishDispatch(ownCache, pairCache, watch.ms());
    stats = outer;
}

void CullideCollisionDispatcher::finishDispatch(bool ownCache, const btOverlappingPairCache* pairCache, double ms) {
    CullideDispatchStats& stats = m_context->stats;
    stats.dispatchMs = ms;
    stats.pairsDispatched = static_cast<std::size_t>(pairCache->getNumOverlappingPairs());
    m_total += stats;
    if (ownCache) m_lastStep = stats;
}

void* CullideCollisionDispatcher::allocateCollisionAlgorithm(int size) {
    // btPoolAllocator only asserts on the size: an algorithm larger than the pool element would silently corrupt
    // memory in release builds. Such algorithms come from the heap (freeCollisionAlgorithm handles both), and so do
    // those made on the narrow-phase threads (a convex-mesh pair's per-triangle ones): the pool is the calling thread's.
    if (bullet::onPairThread() ||
        (m_collisionAlgorithmPoolAllocator != nullptr && size > m_collisionAlgorithmPoolAllocator->getElementSize()))
        return btAlignedAlloc(static_cast<size_t>(size), 16);
    return btCollisionDispatcher::allocateCollisionAlgorithm(size);
}

}  // namespace cullide
