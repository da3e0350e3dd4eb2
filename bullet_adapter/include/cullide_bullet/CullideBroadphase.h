// CullideBroadphase: a drop-in btBroadphaseInterface. Bullet's own broadphase (the object level) finds the object
// pairs; for the kinds of pair a culling switch below covers, CULLIDE's visibility culling decides which triangles of
// each pair can come within the culling margin, and CullideCollisionDispatcher reads that verdict. Every other pair
// goes from the object level straight to Bullet's algorithms.
//
//     auto* broadphase = new cullide::CullideBroadphase();  // was: new btDbvtBroadphase()
//     auto* dispatcher = new cullide::CullideCollisionDispatcher(config, broadphase);
//                                                           // was: new btCollisionDispatcher(config)
//
// bullet_adapter/README.md describes the step, the options, the guarantees and the known differences.
#pragma once

#include "cullide/Culler.h"
#include "cullide/Settings.h"
#include "cullide_bullet/CullideStats.h"
#include "cullide_bullet/Precision.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseInterface.h>
#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#include <LinearMath/btVector3.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

class btCollisionObjectWrapper;
class btCollisionShape;

namespace cullide {

class CullideBroadphase;
namespace bullet {
class PairRecords;  // the per-pair hand-off to CullideCollisionDispatcher (internal: src/broadphase/PairRecords.h)
/// The records of the broadphase's last step, for the dispatcher (internal).
const PairRecords& pairRecordsOf(const CullideBroadphase& broadphase);
}  // namespace bullet

/// A culling switch's setting.
enum class Culling {
    /// Culled where a trial on the running scene shows it pays (CullideBroadphase's culling switches); the default.
    Auto,
    On,    ///< always culled
    Off,   ///< never culled
};
/// The kinds of pair a culling switch covers.
enum class CulledKind {
    /// GImpact mesh against GImpact mesh. Not culled, such a pair gets Bullet's GImpact contacts bit for bit
    /// (CullideCollisionDispatcher reproduces Bullet's box-set search and triangle routine at a fraction of its
    /// cost). Culled, the culler's near triangle pairs go to Bullet's triangle routine; a pair whose meshes
    /// intersect gets Bullet's contacts (setDeepPenetrationFallback), and so does a pair whose near pairs make no
    /// point.
    GImpactPair,
    /// GImpact mesh against a triangle mesh (btBvhTriangleMeshShape, its scaled form). Not culled, Bullet's
    /// contacts point for point (Bullet's gimpact_vs_concave minus candidates too far for any point); culled, the
    /// mesh's triangles are the culler's near ones, in sorted order.
    GImpactMesh,
    /// GImpact mesh against a convex shape (box, sphere, hull, compound of convex children). Culled, a pair the
    /// culler proves farther apart than its margin makes no contact that step; the others, and every pair not
    /// culled, run Bullet's per-triangle loop minus the candidates too far for any point.
    GImpactConvex,
    /// Convex hull or compound against a triangle mesh. Culled, the dispatcher's convex-concave algorithm reads
    /// only the mesh triangles the culler kept near the hull; not culled, Bullet's own algorithm. The algorithm of
    /// a pair is chosen when the pair first appears: a pair made while the switch could not be on (Off, or Auto
    /// where it never trials) keeps Bullet's algorithm.
    ConvexMesh,
};

class CullideBroadphase : public btBroadphaseInterface {
public:
    /// Creates the culler for `settings` (createGpuCuller unless another factory is given).
    using CullerFactory = std::function<std::unique_ptr<Culler>(const Settings&)>;

    /// The culler is made (createGpuCuller: a GL context and worker threads) when a step first has pairs for it (a
    /// culling switch below is On, or Auto where it trials, and such pairs overlap), never in a world without any;
    /// for Auto alone on another thread. Like createGpuCuller,
    /// without a usable GL device it runs its CPU path (a one-line notice); settings that demand GPU levels
    /// (GpuLevels::Always, Pipeline::Paper) make it here, so a missing device throws GlUnavailableError here. A
    /// factory that fails when the culler is made later is reported once on stderr, and the pairs it would have culled
    /// get Bullet's full algorithms. std::invalid_argument for invalid settings. `pairCache`
    /// (optional, not owned) replaces the internal btHashedOverlappingPairCache, like
    /// btDbvtBroadphase(btOverlappingPairCache*).
    explicit CullideBroadphase(const Settings& settings = Settings{}, btOverlappingPairCache* pairCache = nullptr)
        : CullideBroadphase(detail::checkBulletPrecision(), settings, pairCache, CullerFactory{}) {}
    /// Same, with a custom culler factory (e.g. createReferenceCuller for tests without GL).
    CullideBroadphase(const Settings& settings, btOverlappingPairCache* pairCache, CullerFactory factory)
        : CullideBroadphase(detail::checkBulletPrecision(), settings, pairCache, std::move(factory)) {}
    ~CullideBroadphase() override;

    CullideBroadphase(const CullideBroadphase&) = delete;
    CullideBroadphase& operator=(const CullideBroadphase&) = delete;

    // ---- btBroadphaseInterface ----
    btBroadphaseProxy* createProxy(const btVector3& aabbMin, const btVector3& aabbMax, int shapeType, void* userPtr,
                                   int collisionFilterGroup, int collisionFilterMask,
                                   btDispatcher* dispatcher) override;
    void destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) override;
    void setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                 btDispatcher* dispatcher) override;
    void getAabb(btBroadphaseProxy* proxy, btVector3& aabbMin, btVector3& aabbMax) const override;
    void rayTest(const btVector3& rayFrom, const btVector3& rayTo, btBroadphaseRayCallback& rayCallback,
                 const btVector3& aabbMin = btVector3(0, 0, 0),
                 const btVector3& aabbMax = btVector3(0, 0, 0)) override;
    void aabbTest(const btVector3& aabbMin, const btVector3& aabbMax, btBroadphaseAabbCallback& callback) override;
    void calculateOverlappingPairs(btDispatcher* dispatcher) override;
    btOverlappingPairCache* getOverlappingPairCache() override;
    const btOverlappingPairCache* getOverlappingPairCache() const override;
    void getBroadphaseAabb(btVector3& aabbMin, btVector3& aabbMax) const override;
    void resetPool(btDispatcher* dispatcher) override;
    void printStats() override;

    // ---- CULLIDE ----
    /// Drop cached triangle geometry of `shape`. Not needed after deforming a mesh in place: changed vertex data is
    /// detected every step by a content hash.
    void invalidateShape(const btCollisionShape* shape);

    /// With setGImpactPairCulling(true): GImpact-GImpact pairs whose meshes intersect (exact test on the surviving
    /// triangle pairs) get Bullet's GImpact contacts for that step (default: on; without GImpact pair culling every
    /// GImpact-GImpact pair gets them and this setting changes nothing). GImpact's clip method also makes
    /// penetration contacts from triangle pairs that are far apart but whose boxes overlap; only such pairs, deep
    /// inside the other mesh, make them, and CULLIDE's near pairs do not include them. With the fallback the
    /// contacts of interpenetrating pairs are exactly Bullet's; without it they come from the near pairs only (faster
    /// when meshes often intersect, but the deepest penetration can be under-reported). Resting contacts within the
    /// margins are not affected. With the fallback on, a pair found interpenetrating skips the culler for the next 4
    /// steps (Bullet's full algorithm runs it: Bullet's contacts, without paying for culling it would not read), then
    /// is culled again.
    void setDeepPenetrationFallback(bool enable);
    bool getDeepPenetrationFallback() const;

    /// Makes `objectLevel` — any Bullet broadphase, e.g. the btAxisSweep3 an application used before the swap — the
    /// object level instead of the internal btDbvtBroadphase: its pair cache, pairs, rayTest, aabbTest and per-step
    /// cost become this broadphase's, and the CULLIDE levels run on its pairs as on the default one's. Owned from
    /// then on. Only before the first proxy is created (std::logic_error otherwise); std::invalid_argument for null
    /// or for another CullideBroadphase. The pair cache given to the constructor is left unused: give the
    /// replacement its own.
    void setObjectLevel(std::unique_ptr<btBroadphaseInterface> objectLevel);

    // ---- The culling switches: which kinds of pair go through the culler's levels ----
    //
    // Each kind of pair (CulledKind) has a switch (Culling): On culls every such pair, Off none, Auto (the default)
    // culls them where a trial on the running scene shows it pays. Auto trials only on a machine with a hardware GL
    // device (hasHardwareGlDevice for Settings::device), unless setAutoCullingOnAnyDevice(true); elsewhere it never
    // culls, makes no culler and opens no GL context, and every pair gets the unculled path (Bullet's contacts bit
    // for bit). Where it trials, the culler is made on another thread (no step waits for it), then each kind with
    // pairs is timed in turn: a step with the kind not culled, a warm-up step culled, a timed step culled; the kind
    // is culled from then on if the timed step (culling plus narrow phase) cost less. A culled trial step gives the
    // culler at most the unculled step's cost plus 1 ms, then abandons it (its pairs run Bullet's algorithms): no
    // trial step costs more than about twice a step without it plus 1 ms. The decision holds until the kind's pair
    // count halves or doubles (at least 120 steps; longer while the same decision keeps winning by at least twice).
    // getCullingDecision reports the state and the trial's timings. A culled pair gets a point in every step in which
    // Bullet's pipeline gives it one (the culling margin rule: docs/architecture.md); its points can differ from
    // Bullet's (docs/swap.md reports by how much).

    void setCulling(CulledKind kind, Culling mode);
    Culling getCulling(CulledKind kind) const;
    /// Whether pairs of the kind are culled in the step under way (On, or Auto's current decision).
    bool isCulled(CulledKind kind) const;
    /// Whether pairs of the kind may be culled in some step: On, or Auto where it trials.
    bool mayCull(CulledKind kind) const;
    /// What Culling::Auto decided for the kind, with the timings behind it.
    CullingDecision getCullingDecision(CulledKind kind) const;
    /// Culling::Auto trials wherever the culler runs (its CPU path, a software renderer), not only on a machine with a
    /// hardware GL device (default: false). For measuring, or an application that knows culling pays on its CPU.
    void setAutoCullingOnAnyDevice(bool enable);

    /// The switches by kind, as setCulling; `true` is Culling::On, `false` Culling::Off. The getters say whether the
    /// kind is culled in the step under way (isCulled).
    void setGImpactPairCulling(Culling mode) { setCulling(CulledKind::GImpactPair, mode); }
    void setGImpactPairCulling(bool on) { setGImpactPairCulling(on ? Culling::On : Culling::Off); }
    bool getGImpactPairCulling() const { return isCulled(CulledKind::GImpactPair); }
    void setGImpactMeshCulling(Culling mode) { setCulling(CulledKind::GImpactMesh, mode); }
    void setGImpactMeshCulling(bool on) { setGImpactMeshCulling(on ? Culling::On : Culling::Off); }
    bool getGImpactMeshCulling() const { return isCulled(CulledKind::GImpactMesh); }
    void setGImpactConvexCulling(Culling mode) { setCulling(CulledKind::GImpactConvex, mode); }
    void setGImpactConvexCulling(bool on) { setGImpactConvexCulling(on ? Culling::On : Culling::Off); }
    bool getGImpactConvexCulling() const { return isCulled(CulledKind::GImpactConvex); }
    void setConvexMeshCulling(Culling mode) { setCulling(CulledKind::ConvexMesh, mode); }
    void setConvexMeshCulling(bool on) { setConvexMeshCulling(on ? Culling::On : Culling::Off); }
    bool getConvexMeshCulling() const { return isCulled(CulledKind::ConvexMesh); }

    const CullideFrameStats& getLastFrameStats() const;
    /// What is kept between steps (computed on each call: a pass over the kept objects and shapes).
    CullideMemoryStats getMemoryStats() const;
    /// Number of rejected non-finite AABBs (createProxy/setAabb calls) and geometry since construction.
    std::size_t getRejectedCount() const;
    /// The culler's current distance margin d (0 before the culler is made).
    double getCullingMargin() const;
    const Settings& getSettings() const;

private:
    friend const bullet::PairRecords& bullet::pairRecordsOf(const CullideBroadphase& broadphase);

    CullideBroadphase(detail::PrecisionChecked, const Settings& settings, btOverlappingPairCache* pairCache,
                      CullerFactory factory);

    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide
