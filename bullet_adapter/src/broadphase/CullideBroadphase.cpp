#include "cullide_bullet/CullideBroadphase.h"
#include "cullide/Timer.h"

#include "broadphase/BulletProxies.h"
#include "broadphase/CullFrame.h"
#include "broadphase/CullerSlot.h"
#include "broadphase/CullingPolicy.h"
#include "broadphase/CullingSwitches.h"
#include "broadphase/ObjectLevel.h"
#include "broadphase/PairRecords.h"
#include "broadphase/PairTriangles.h"
#include "broadphase/ShapeGeometry.h"
#include "cullide/Result.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

namespace cullide {

int detail::bulletScalarSizeOfLibrary() noexcept { return static_cast<int>(sizeof(btScalar)); }

namespace {

using bullet::objectOf;
using bullet::shapeOf;

/// AABB coordinates beyond this are "infinite" (btStaticPlaneShape reports +-BT_LARGE_FLOAT = 1e18 in float builds):
/// such objects are never handed to the culler; their pairs go to Bullet's algorithms as they are.
constexpr double kInfiniteCoordinate = 1e15;
/// The margin of a culler made at construction (settings that demand GPU levels, CullerSlot.h) when Settings::margin
/// is 0; the first step recreates it with exactly the margin the scene needs (cullingMarginToMake).
constexpr double kDefaultMargin = 0.12;

bool infiniteBox(const btBroadphaseProxy* p) {
    for (int a = 0; a < 3; ++a)
        if (std::fabs(double(p->m_aabbMin[a])) > kInfiniteCoordinate ||
            std::fabs(double(p->m_aabbMax[a])) > kInfiniteCoordinate)
            return true;
    return false;
}

bullet::BreakingRule breakingRule(const btDispatcher* dispatcher) {
    const auto* collisionDispatcher = dynamic_cast<const btCollisionDispatcher*>(dispatcher);
    bullet::BreakingRule rule;
    rule.threshold = double(gContactBreakingThreshold);
    rule.relative = collisionDispatcher == nullptr ||
                    (collisionDispatcher->getDispatcherFlags() &
                     btCollisionDispatcher::CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD) != 0;
    rule.epsilon = double(std::numeric_limits<btScalar>::epsilon());
    return rule;
}

}  // namespace

/// The parts, each with one job: the object level (Bullet's btDbvtBroadphase and the parking of non-finite boxes,
/// ObjectLevel.h), the culler and its margin (CullerSlot.h, CullingPolicy.h), the culling frame built from the
/// culled pairs (CullFrame.h) and the records handed to the dispatcher (PairRecords.h, which states the contract).
/// This class only orders them within a step: the object level's pairs, the pairs that go through the culler
/// (collectCandidates), the frame, the culler, the verdicts. A pair the culler proves farther apart than the margin
/// stays in the cache, as in Bullet, and its narrow phase reports nothing.
struct CullideBroadphase::Impl {
    bullet::ObjectLevel objectLevel;
    bullet::CullerSlot culler;
    bullet::CullFrame cullFrame;
    bullet::PairRecords records;
    bullet::CullingSwitches switches;
    /// This step's cache pairs of a kind that may be culled, with their kind; and of those, the ones culled.
    std::vector<std::pair<bullet::CullFrame::ProxyPair, CulledKind>> possiblePairs;
    std::vector<bullet::CullFrame::ProxyPair> candidates;
    Result result;
    CullideFrameStats stats;
    std::uint64_t step = 0;
    std::size_t cullerRejections = 0;  ///< objects the culler rejected, every step (getRejectedCount)
    bool deepPenetrationFallback = true;

    Impl(const Settings& s, btOverlappingPairCache* pairCache, CullerFactory f)
        : objectLevel(pairCache), culler(s, std::move(f), kDefaultMargin), switches(s.device) {}

    void destroyProxy(btBroadphaseProxy* p, btDispatcher* dispatcher) {
        cullFrame.forget(p);
        records.forgetProxy(p);
        objectLevel.destroyProxy(p, dispatcher);
    }

    /// The culling switch that covers the pair, among `kinds`; never for parked objects or infinite boxes (planes,
    /// huge AABBs: Bullet's algorithms).
    std::optional<CulledKind> kindOf(const btBroadphaseProxy* a, const btBroadphaseProxy* b,
                                     const bullet::CulledKinds& kinds) const {
        const btCollisionShape* sa = shapeOf(a);
        const btCollisionShape* sb = shapeOf(b);
        if (sa == nullptr || sb == nullptr) return std::nullopt;
        // Every culled pair has a GImpact shape, or a triangle mesh: most pairs stop here.
        auto mayBe = [&](const btCollisionShape* s) {
            const int type = s->getShapeType();
            return type == GIMPACT_SHAPE_PROXYTYPE || (kinds[CulledKind::ConvexMesh] && bullet::isTriangleMeshType(type));
        };
        if (!mayBe(sa) && !mayBe(sb)) return std::nullopt;
        const std::optional<CulledKind> kind = bullet::culledKindOf(bullet::geometryKindOf(sa), sa->isConvex(),
                                                                    bullet::geometryKindOf(sb), sb->isConvex());
        if (!kind || !kinds[*kind]) return std::nullopt;
        if (objectLevel.isParked(a) || objectLevel.isParked(b) || infiniteBox(a) || infiniteBox(b)) return std::nullopt;
        return kind;
    }

    /// The pairs of the cache that may be culled this step, and their count per kind; pairs the dispatcher will not
    /// process (needsCollision: both asleep, collide-with exclusions) cost nothing.
    bullet::AutoCulling::Counts collectPossible(btDispatcher* dispatcher) {
        possiblePairs.clear();
        bullet::AutoCulling::Counts counts{};
        btOverlappingPairCache* pairs = objectLevel.cache();
        const int n = pairs->getNumOverlappingPairs();
        if (n == 0) return counts;
        const bullet::CulledKinds kinds = switches.possible();
        if (!kinds.any()) return counts;  // no switch can be on: no scan of the cache's pairs at all
        btBroadphasePair* array = pairs->getOverlappingPairArrayPtr();
        for (int i = 0; i < n; ++i) {
            btBroadphaseProxy* a = array[i].m_pProxy0;
            btBroadphaseProxy* b = array[i].m_pProxy1;
            if (a == nullptr || b == nullptr) continue;
            const std::optional<CulledKind> kind = kindOf(a, b, kinds);
            if (!kind) continue;
            if (dispatcher != nullptr && !dispatcher->needsCollision(objectOf(a), objectOf(b))) continue;
            possiblePairs.emplace_back(bullet::CullFrame::ProxyPair(a, b), *kind);
            ++counts[static_cast<std::size_t>(*kind)];
        }
        return counts;
    }

    /// Of the possible pairs, those of the kinds culled this step (of a kind in an Auto trial's ramp, its first
    /// ones); pairs recently found interpenetrating are recorded as such without culling.
    void collectCandidates(const bullet::AutoCulling::Counts& counts) {
        candidates.clear();
        const bullet::CulledKinds& culled = switches.culled();
        bullet::AutoCulling::Counts left{};
        for (std::size_t k = 0; k < left.size(); ++k) left[k] = switches.pairsToCull(CulledKind(k), counts[k]);
        for (const auto& [pair, kind] : possiblePairs) {
            if (!culled[kind] || left[static_cast<std::size_t>(kind)] == 0) continue;
            --left[static_cast<std::size_t>(kind)];
            if (records.recentlyPenetrating(pair.first, pair.second)) {
                records.recordPenetrating(pair.first, pair.second);
                ++stats.penetratingSkipped;
                continue;
            }
            candidates.push_back(pair);
        }
    }

    void reportRejected(const ObjectDiagnostic& d) {
        btBroadphaseProxy* p = cullFrame.proxyOf(d.object);
        bullet::CulledObject& c = cullFrame.culled(p);
        ++stats.rejectedObjects;
        ++cullerRejections;
        if (c.reported) return;
        c.reported = true;
        std::fprintf(stderr,
                     "cullide::CullideBroadphase: collision object %p (proxy %d) rejected by the culler: %s. Its "
                     "culled pairs get no contacts; every other object is unaffected. (Reported once per object.)\n",
                     static_cast<const void*>(objectOf(p)), p->m_uniqueId, d.message.c_str());
    }

    /// The culler over this step's culled pairs, and its verdicts recorded for the dispatcher. Without a culler
    /// (it could not be made, it failed, or Auto's is still being made) the pairs get no record: Bullet's full
    /// algorithms run for them.
    void cullCandidates(btDispatcher* dispatcher, cullide::Timer& build) {
        cullFrame.build(candidates, step, stats);
        const double required = bullet::requiredCullingMargin(cullFrame.marginEntries(), cullFrame.pairs(), breakingRule(dispatcher));
        // An On switch makes its culler here; Auto's is made on another thread, and the step waits for nothing.
        const bool ready = switches.anyOn() ? culler.ready(required, step) : culler.readyWithoutWaiting(required, step);
        if (!ready) switches.cancelStep();
        stats.buildMs = build.ms();
        cullide::Timer cull;
        const bool ran = ready && culler.run(cullFrame.objects(), cullFrame.pairs(), result, switches.cullerBudgetMs());
        stats.cullMs = cull.ms();
        stats.culler = result.stats;
        const bool verdicts = ran && !result.stats.abandoned;
        if (!verdicts) result.clear();
        for (const auto& list : result.pcsTriangles) stats.pcsTriangles += list.size();
        cullide::Timer recordTimer;
        if (verdicts) {
            for (const ObjectDiagnostic& d : result.rejected) reportRejected(d);
            records.recordVerdicts(result, cullFrame, deepPenetrationFallback, stats);
        }
        stats.recordMs = recordTimer.ms();
    }

    /// Culling::Auto's culler, made on another thread for the Auto kinds' pairs of this step (none is culled yet).
    void prepareAutoCuller(btDispatcher* dispatcher) {
        candidates.clear();
        for (const auto& [pair, kind] : possiblePairs)
            if (switches.get(kind) == Culling::Auto) candidates.push_back(pair);
        cullFrame.build(candidates, step, stats);
        culler.readyWithoutWaiting(
            bullet::requiredCullingMargin(cullFrame.marginEntries(), cullFrame.pairs(), breakingRule(dispatcher)), step);
        stats.culledObjects = stats.culledPairs = stats.meshObjects = stats.triangles = 0;
    }

    /// The previous step's cost for Culling::Auto: the broadphase's culling and the dispatcher's narrow phase.
    void finishPreviousStep(btDispatcher* dispatcher) {
        const auto* cullide = dynamic_cast<const CullideCollisionDispatcher*>(dispatcher);
        const double narrowMs = cullide != nullptr ? cullide->getLastStepStats().dispatchMs : 0.0;
        switches.endStep(stats.buildMs + stats.cullMs + stats.recordMs + narrowMs, stats.culler.abandoned);
    }

    void calculateOverlappingPairs(btDispatcher* dispatcher) {
        cullide::Timer total;
        if (step > 0) finishPreviousStep(dispatcher);
        ++step;
        stats = CullideFrameStats{};
        records.beginStep(step, deepPenetrationFallback);
        cullFrame.beginStep();

        cullide::Timer objectTimer;
        objectLevel.tree().calculateOverlappingPairs(dispatcher);
        stats.objectLevelMs = objectTimer.ms();
        stats.proxies = objectLevel.proxyCount();
        stats.objectPairs = static_cast<std::size_t>(objectLevel.cache()->getNumOverlappingPairs());
        stats.rejectedObjects = objectLevel.parkedCount();

        cullide::Timer build;
        const bullet::AutoCulling::Counts counts = collectPossible(dispatcher);
        const bool measurable = dynamic_cast<const CullideCollisionDispatcher*>(dispatcher) != nullptr;
        switches.beginStep(counts, culler.hasCuller(), measurable);
        collectCandidates(counts);
        if (!candidates.empty())
            cullCandidates(dispatcher, build);
        else if (!culler.hasCuller() && switches.wantsCuller(counts))
            prepareAutoCuller(dispatcher);
        stats.margin = culler.margin();
        stats.totalMs = total.ms();
    }
};

CullideBroadphase::CullideBroadphase(detail::PrecisionChecked, const Settings& settings,
                                     btOverlappingPairCache* pairCache, CullerFactory factory)
    : m_impl(std::make_unique<Impl>(settings, pairCache, std::move(factory))) {}

CullideBroadphase::~CullideBroadphase() = default;

btBroadphaseProxy* CullideBroadphase::createProxy(const btVector3& aabbMin, const btVector3& aabbMax, int shapeType,
                                                  void* userPtr, int collisionFilterGroup, int collisionFilterMask,
                                                  btDispatcher* dispatcher) {
    return m_impl->objectLevel.createProxy(aabbMin, aabbMax, shapeType, userPtr, collisionFilterGroup, collisionFilterMask,
                               dispatcher);
}

void CullideBroadphase::destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) {
    m_impl->destroyProxy(proxy, dispatcher);
}

void CullideBroadphase::setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                                btDispatcher* dispatcher) {
    m_impl->objectLevel.setAabb(proxy, aabbMin, aabbMax, dispatcher);
}

void CullideBroadphase::getAabb(btBroadphaseProxy* proxy, btVector3& aabbMin, btVector3& aabbMax) const {
    m_impl->objectLevel.tree().getAabb(proxy, aabbMin, aabbMax);
}

void CullideBroadphase::rayTest(const btVector3& rayFrom, const btVector3& rayTo, btBroadphaseRayCallback& rayCallback,
                                const btVector3& aabbMin, const btVector3& aabbMax) {
    m_impl->objectLevel.tree().rayTest(rayFrom, rayTo, rayCallback, aabbMin, aabbMax);
}

void CullideBroadphase::aabbTest(const btVector3& aabbMin, const btVector3& aabbMax,
                                 btBroadphaseAabbCallback& callback) {
    m_impl->objectLevel.tree().aabbTest(aabbMin, aabbMax, callback);
}

void CullideBroadphase::calculateOverlappingPairs(btDispatcher* dispatcher) {
    m_impl->calculateOverlappingPairs(dispatcher);
}

btOverlappingPairCache* CullideBroadphase::getOverlappingPairCache() { return m_impl->objectLevel.cache(); }
const btOverlappingPairCache* CullideBroadphase::getOverlappingPairCache() const {
    return m_impl->objectLevel.cache();
}

void CullideBroadphase::getBroadphaseAabb(btVector3& aabbMin, btVector3& aabbMax) const {
    m_impl->objectLevel.tree().getBroadphaseAabb(aabbMin, aabbMax);
}

void CullideBroadphase::resetPool(btDispatcher* dispatcher) {
    m_impl->objectLevel.tree().resetPool(dispatcher);
    if (m_impl->objectLevel.proxyCount() != 0) return;
    m_impl->records.clear();
    m_impl->cullFrame.clear();
}

void CullideBroadphase::printStats() {
    const CullideFrameStats& s = m_impl->stats;
    std::printf(
        "CullideBroadphase: %zu proxies, %zu object pairs (%zu culled, %zu pruned, %zu kept), %zu culled objects "
        "(%zu meshes, %zu triangles), %zu rejected; %zu triangle pairs, %zu interpenetrating, margin %.4g; object "
        "level %.3f ms, build %.3f ms, cull %.3f ms, records %.3f ms, total %.3f ms\n",
        s.proxies, s.objectPairs, s.culledPairs, s.prunedPairs, s.cullerPairs, s.culledObjects, s.meshObjects,
        s.triangles, s.rejectedObjects, s.trianglePairs, s.interpenetratingPairs, s.margin, s.objectLevelMs,
        s.buildMs, s.cullMs, s.recordMs, s.totalMs);
}

const bullet::PairRecords& bullet::pairRecordsOf(const CullideBroadphase& broadphase) {
    return broadphase.m_impl->records;
}

void CullideBroadphase::invalidateShape(const btCollisionShape* shape) {
    m_impl->cullFrame.invalidateShape(shape);
}

void CullideBroadphase::setDeepPenetrationFallback(bool enable) { m_impl->deepPenetrationFallback = enable; }
bool CullideBroadphase::getDeepPenetrationFallback() const { return m_impl->deepPenetrationFallback; }


void CullideBroadphase::setObjectLevel(std::unique_ptr<btBroadphaseInterface> objectLevel) {
    if (objectLevel == nullptr) throw std::invalid_argument("CullideBroadphase::setObjectLevel: null broadphase");
    if (dynamic_cast<CullideBroadphase*>(objectLevel.get()) != nullptr)
        throw std::invalid_argument("CullideBroadphase::setObjectLevel: the object level must be a Bullet broadphase, "
                                    "not another CullideBroadphase");
    if (m_impl->objectLevel.proxyCount() != 0)
        throw std::logic_error("CullideBroadphase::setObjectLevel: proxies exist already; set the object level "
                               "before adding collision objects");
    m_impl->objectLevel.replace(std::move(objectLevel));
}

void CullideBroadphase::setCulling(CulledKind kind, Culling mode) { m_impl->switches.set(kind, mode); }
Culling CullideBroadphase::getCulling(CulledKind kind) const { return m_impl->switches.get(kind); }
bool CullideBroadphase::isCulled(CulledKind kind) const { return m_impl->switches.isCulled(kind); }
bool CullideBroadphase::mayCull(CulledKind kind) const { return m_impl->switches.possible()[kind]; }
CullingDecision CullideBroadphase::getCullingDecision(CulledKind kind) const {
    return m_impl->switches.decision(kind);
}
void CullideBroadphase::setAutoCullingOnAnyDevice(bool enable) { m_impl->switches.setAutoOnAnyDevice(enable); }

const CullideFrameStats& CullideBroadphase::getLastFrameStats() const { return m_impl->stats; }
CullideMemoryStats CullideBroadphase::getMemoryStats() const { return m_impl->cullFrame.memory(); }
std::size_t CullideBroadphase::getRejectedCount() const {
    return m_impl->objectLevel.parkCalls() + m_impl->cullerRejections;
}
double CullideBroadphase::getCullingMargin() const { return m_impl->culler.margin(); }
const Settings& CullideBroadphase::getSettings() const { return m_impl->culler.settings(); }

}  // namespace cullide
