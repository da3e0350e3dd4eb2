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

class CullideBroadphase : public btBroadphaseInterface {
public:
    /// Creates the culler for `settings` (createGpuCuller unless another factory is given).
    using CullerFactory = std::function<std::unique_ptr<Culler>(const Settings&)>;

    /// The culler is made (createGpuCuller: a GL context and worker threads) when a step first has pairs for it (a
    /// culling switch below is on and such pairs overlap), never in a world without any. Like createGpuCuller,
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

    /// Convex hulls and compounds against triangle meshes through the culler's levels (default: off). On, the
    /// dispatcher's convex-concave algorithm reads only the mesh triangles CULLIDE kept near the hull; off, such
    /// pairs go from the object level straight to Bullet's algorithm, whose own BVH query of the mesh is already
    /// cheap: measured on 1,000 hulls over a 32K-triangle landscape (docs/swap.md), the
    /// culling costs more than the narrow phase it saves on the CPU path (GImpact pairs: setGImpactPairCulling,
    /// setGImpactMeshCulling, setGImpactConvexCulling). Set it
    /// before the first step: CullideCollisionDispatcher picks the culled hull/compound-mesh algorithm when a pair's
    /// algorithm is created (pairs created while it is off keep Bullet's own algorithm, which stays correct).
    void setConvexMeshCulling(bool enable);
    bool getConvexMeshCulling() const;

    /// GImpact-GImpact pairs through the culler's levels (default: off). Off, such a pair gets Bullet's GImpact
    /// contacts bit for bit: CullideCollisionDispatcher runs Bullet's own box-set pair search and triangle routine,
    /// reproduced at a fraction of Bullet's cost (the same triangle pairs in the same order, each triangle mapped to
    /// world space once per pair of bodies instead of once per triangle pair). On, the culler's near triangle pairs
    /// replace Bullet's box-overlapping ones for pairs whose meshes do not intersect (setDeepPenetrationFallback for
    /// those that do): Bullet's clip method then no longer makes its contacts from triangle pairs whose boxes overlap
    /// without the triangles coming near (phantom points up to a box deep), and the manifold's other points can
    /// differ. Measured on the tori pile (docs/swap.md): on costs the culling and saves no narrow-phase time, so
    /// the default is off.
    void setGImpactPairCulling(bool enable);
    bool getGImpactPairCulling() const;

    /// GImpact meshes against triangle meshes (btBvhTriangleMeshShape, btScaledBvhTriangleMeshShape) through the
    /// culler's levels (default: off). Off, such a pair gets Bullet's contacts point for point:
    /// CullideCollisionDispatcher runs Bullet's own gimpact_vs_concave (the mesh's triangles within the GImpact part's
    /// box, in Bullet's order, each against the GImpact part's box-query candidates through the convex algorithm),
    /// skipping the candidates too far from the mesh triangle for any point — Bullet runs GJK on each. The same holds
    /// for GImpact against other concave shapes (heightfields; not planes: Bullet's own), never culled. On, the mesh's
    /// triangles are the culler's near ones in sorted order instead of Bullet's query: the 4-point manifold can keep
    /// other points, and the culling costs more than it saves on the CPU path (docs/swap.md, 'gimpact-landscape').
    /// Set it before the first step.
    void setGImpactMeshCulling(bool enable);
    bool getGImpactMeshCulling() const;

    /// GImpact meshes against convex shapes (boxes, spheres, hulls, compounds of convex children) decided by the
    /// culler (default: off). On, a pair the culler proves farther apart than its margin makes no contact that step
    /// and the others run the dispatcher's loop; off, every pair runs it: Bullet's per-triangle loop (its box query,
    /// then GJK per candidate triangle, Bullet's contacts point for point) minus the candidates too far from the
    /// convex shape for any point. Measured on the CPU path (docs/swap.md) the culling costs more than
    /// the loop it saves. Set it before the first step.
    void setGImpactConvexCulling(bool enable);
    bool getGImpactConvexCulling() const;

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
