// CullideBroadphase: a drop-in btBroadphaseInterface whose mesh pairs are decided by CULLIDE (image-space
// visibility culling, GPU levels where they pay) instead of AABB overlap alone.
//
//     auto* broadphase = new cullide::CullideBroadphase();  // was: new btDbvtBroadphase()
//     auto* dispatcher = new cullide::CullideCollisionDispatcher(config, broadphase);
//                                                           // was: new btCollisionDispatcher(config)
//
// Design (see bullet_adapter/README.md for the details and the limits):
// - The object level is Bullet's own btDbvtBroadphase, owned by this class: the pair cache holds exactly the pairs
//   Bullet's default pipeline would (filters, the overlap filter callback, static and kinematic objects in
//   collision-only worlds, ghost objects, planes, fattened leaves, lazy removal), objects that did not move cost
//   nothing, and rayTest / aabbTest answer as Bullet's. An application that used another Bullet broadphase (a
//   btAxisSweep3 with its world bounds, a tuned btDbvtBroadphase) hands it over with setObjectLevel and keeps its
//   pairs and its costs. A proxy with a non-finite AABB is parked (one line on stderr,
//   a counter, no pairs, its filter mask left alone) instead of poisoning the tree. The valid objects keep their
//   pairs and contacts; the manifolds' order (which the solver follows) may differ from Bullet's from then on.
// - The CULLIDE levels run only for the kinds of pair the application switches on (all off by default: then no
//   culler is ever made, no GL context opened): GImpact-triangle mesh (plain or btScaledBvhTriangleMeshShape) with
//   setGImpactMeshCulling(true), GImpact-GImpact with setGImpactPairCulling(true), hull/compound-triangle mesh with
//   setConvexMeshCulling(true), whose narrow phase reads the surviving triangles, and GImpact against a convex shape
//   with setGImpactConvexCulling(true), which the culler decides; and only for pairs the dispatcher will process
//   (needsCollision). The culler gets those pairs only, meshes
//   as the shape's local triangles plus the body's transform (built once per shape, shared by its bodies; static
//   objects world-space, cached between steps). Planes and infinite boxes are never culled. Every other pair goes
//   from the object level straight to Bullet's algorithms.
// - The hand-off to CullideCollisionDispatcher is a per-pair record (internal), valid only for the shapes
//   and transforms the pair had in calculateOverlappingPairs(): the surviving triangles, or `pruned` for a pair the
//   culler proved farther apart than its margin (it stays in the cache, as in Bullet; the narrow phase makes no
//   contact for it). A pair without a record runs Bullet's own algorithm.
// - The culler's distance margin d is what the frame's narrow phase needs, recomputed every step: for GImpact
//   pairs 2.2 * the largest GImpact margin (plus float slack at large coordinates; GImpact's triangle routine
//   reports points within the sum of the two margins and rebuilds its manifold every frame), for pairs with
//   persistent convex manifolds the margins plus 1.5 * the contact breaking threshold (size-relative, as Bullet's
//   dispatcher computes it by default). Every triangle pair that Bullet's narrow phase could turn into a contact
//   point, or keep a persistent one alive, survives. Bullet's own triangle routines are the exact test (the culler
//   runs with Settings::exactTriangles = false). GImpact-GImpact pairs (by default not culled, and culled ones that
//   interpenetrate: setDeepPenetrationFallback) get Bullet's GImpact contacts bit for bit: the dispatcher runs
//   Bullet's pair search and triangle routine, reproduced at a fraction of Bullet's cost.
#pragma once

#include "cullide/Culler.h"
#include "cullide/Settings.h"
#include "cullide/Stats.h"
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

struct PairTriangles;  // the hand-off to CullideCollisionDispatcher (internal: bullet_adapter/src/PairTriangles.h)
namespace detail {
struct AdapterAccess;  // the broadphase's and dispatcher's internal calls (bullet_adapter/src/AdapterAccess.h)
}

/// Statistics of the last calculateOverlappingPairs().
struct CullideFrameStats {
    std::size_t proxies = 0;
    /// Object level (Bullet's btDbvtBroadphase): pairs in the cache.
    std::size_t objectPairs = 0;
    /// ... of which went through the culler (their narrow phase reads triangles, or the culler decides them).
    std::size_t culledPairs = 0;
    /// ... of which the culler proved farther apart than the margin: recorded as pruned, no contact this step.
    std::size_t prunedPairs = 0;
    std::size_t cullerPairs = 0;         ///< culled pairs the culler kept
    std::size_t culledObjects = 0;       ///< objects handed to the culler (those of culled pairs)
    std::size_t meshObjects = 0;         ///< ... of which with triangle geometry
    std::size_t triangles = 0;           ///< triangles handed to the culler
    std::size_t rejectedObjects = 0;     ///< parked (non-finite AABB) or rejected by the culler this frame
    std::size_t pcsTriangles = 0;        ///< triangles that survived culling (the triangle-level PCS), all objects
    std::size_t trianglePairs = 0;       ///< surviving triangle pairs kept for the dispatcher
    std::size_t interpenetratingPairs = 0;  ///< GImpact pairs whose meshes intersect (see setDeepPenetrationFallback)
    /// GImpact pairs that interpenetrated in one of the last 4 steps: not culled, Bullet's full algorithm (with the
    /// fallback on, such a pair reads nothing the culler computes; it is culled again after 4 steps).
    std::size_t penetratingSkipped = 0;
    double margin = 0.0;                 ///< the culler's distance margin d this frame
    double objectLevelMs = 0.0;          ///< btDbvtBroadphase::calculateOverlappingPairs
    double buildMs = 0.0;                ///< finding the culled pairs and building the culling frame
    double cullMs = 0.0;                 ///< culler run
    double recordMs = 0.0;               ///< records for the dispatcher
    double totalMs = 0.0;
    Stats culler;                        ///< the culler's own statistics
};

/// What the broadphase keeps between steps for the objects that took part in culled pairs (getMemoryStats): local
/// triangle geometry once per shape, however many bodies share it, and per object its record (transform, keys) plus
/// a world-space copy of its triangles where one is kept (resting static-flagged objects; with
/// setGImpactPairCulling(true), objects whose pairs the broadphase tests itself). Heap bytes of the containers
/// (capacity), not counting the culler's own caches.
struct CullideMemoryStats {
    std::size_t shapes = 0;               ///< shapes with local geometry (each held once)
    std::size_t sharedGeometryBytes = 0;  ///< their vertices, triangles and Bullet ids, in both precisions
    std::size_t objects = 0;              ///< objects kept
    std::size_t objectBytes = 0;          ///< their records and world-space copies
    std::size_t worldCopies = 0;          ///< objects holding a world-space copy
};

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
    /// cheap: measured on 1,000 hulls over a 32K-triangle landscape (docs/benchmarks.md, cullide-swap-bench), the
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
    /// differ. Measured on the tori pile (docs/drop-in.md): on costs the culling and saves no narrow-phase time, so
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
    /// other points, and the culling costs more than it saves on the CPU path (docs/drop-in.md, 'gimpact-landscape').
    /// Set it before the first step.
    void setGImpactMeshCulling(bool enable);
    bool getGImpactMeshCulling() const;

    /// GImpact meshes against convex shapes (boxes, spheres, hulls, compounds of convex children) decided by the
    /// culler (default: off). On, a pair the culler proves farther apart than its margin makes no contact that step
    /// and the others run the dispatcher's loop; off, every pair runs it: Bullet's per-triangle loop (its box query,
    /// then GJK per candidate triangle, Bullet's contacts point for point) minus the candidates too far from the
    /// convex shape for any point. Measured on the CPU path (docs/drop-in.md, session 17) the culling costs more than
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
    friend struct detail::AdapterAccess;
    /// The record of the pair of the two wrapped objects made by the last calculateOverlappingPairs(), while it
    /// holds (bullet_adapter/src/PairRecords.h states the contract), or nullptr. `swapped` is set when body0Wrap is
    /// the record's second object.
    const PairTriangles* trianglePairsFor(const btCollisionObjectWrapper* body0Wrap,
                                          const btCollisionObjectWrapper* body1Wrap, bool& swapped) const;

    CullideBroadphase(detail::PrecisionChecked, const Settings& settings, btOverlappingPairCache* pairCache,
                      CullerFactory factory);

    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide
