#include "cullide_bullet/CullideBroadphase.h"
#include "cullide/Timer.h"

#include "CullingPolicy.h"
#include "ShapeGeometry.h"
#include "cullide/Result.h"
#include "cullide/TriangleTest.h"

#include <BulletCollision/BroadphaseCollision/btDbvt.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>

#include <algorithm>
#include <limits>
#include <map>
#include <cmath>
#include <cstdio>
#include <new>
#include <string>
#include <unordered_map>
#include <utility>

namespace cullide {

int detail::bulletScalarSizeOfLibrary() noexcept { return static_cast<int>(sizeof(btScalar)); }

namespace {

/// AABB coordinates beyond this are "infinite" (btStaticPlaneShape reports +-BT_LARGE_FLOAT = 1e18 in float builds).
constexpr double kInfiniteCoordinate = 1e15;
/// Fattening of the query tree's leaves (like btDbvtBroadphase's gDbvtMargin): fewer tree updates.
constexpr btScalar kTreeMargin = btScalar(0.05);
/// Used for the constructor's culler when Settings::margin is 0 (it must exist to report a missing GL device at
/// construction); the first frame recreates it with exactly the margin the scene needs (see requiredMargin).
constexpr double kDefaultMargin = 0.12;


enum class Role : std::uint8_t { Invalid, Infinite, Ghost, Dynamic, Static };

/// The object level's two trees, as btDbvtBroadphase's two sets: proxies whose leaf moved in the last
/// kSettleFrames frames, and the others (static, sleeping, or moving within their fattened leaf).
enum TreeId : int { kDestroyed = -2, kNoTree = -1, kMovingTree = 0, kRestingTree = 1 };
constexpr std::uint64_t kSettleFrames = 2;

/// Not handed to the culler this frame.
constexpr std::uint32_t kNotCulled = ~std::uint32_t(0);

struct Proxy : btBroadphaseProxy {
    Proxy(const btVector3& aabbMin, const btVector3& aabbMax, void* userPtr, int group, int mask, int type)
        : btBroadphaseProxy(aabbMin, aabbMax, userPtr, group, mask), shapeType(type) {}

    int shapeType;
    btDbvtNode* leaf = nullptr;
    int treeId = kNoTree;  ///< the tree holding `leaf`
    std::uint64_t movedFrame = 0;  ///< the frame in which its leaf last moved (or its role or kind changed)
    std::size_t slot = 0;
    bool valid = true;
    bool reported = false;
    std::uint64_t key = 0;  ///< staticKey for the culler (never reused)

    // Triangle geometry (shared per shape), the transform that places it for the culler (moving objects) and a
    // world-space copy (static objects, and pairs whose triangles the broadphase itself tests: built on demand).
    std::shared_ptr<bullet::ShapeTriangles> geometry;
    Transform toWorld;
    TriangleMesh world;
    btTransform worldFrom;
    bool worldValid = false;
    std::uint64_t version = 0;

    // Per-frame scratch.
    Role role = Role::Invalid;
    bullet::GeometryKind kind = bullet::GeometryKind::None;
    bool convex = false;  ///< its shape is convex (btCollisionShape::isConvex)
    Role lastRole = Role::Invalid;
    bullet::GeometryKind lastKind = bullet::GeometryKind::None;
    std::uint32_t cullIndex = kNotCulled;  ///< index in the culling frame's objects
    bool pairsWithStatics = false;  ///< static, and its filter admits some other static object (every step)
};

btCollisionObject* objectOf(const btBroadphaseProxy* p) { return static_cast<btCollisionObject*>(p->m_clientObject); }

bool finiteBox(const btVector3& mn, const btVector3& mx) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(mn[a]) || !std::isfinite(mx[a])) return false;
    return true;
}

bool boxesOverlap(const btBroadphaseProxy* a, const btBroadphaseProxy* b, btScalar grow = 0) {
    for (int i = 0; i < 3; ++i)
        if (a->m_aabbMin[i] - grow > b->m_aabbMax[i] || b->m_aabbMin[i] - grow > a->m_aabbMax[i]) return false;
    return true;
}

std::uint64_t pairKey(const btBroadphaseProxy* a, const btBroadphaseProxy* b) {
    auto x = static_cast<std::uint32_t>(a->m_uniqueId);
    auto y = static_cast<std::uint32_t>(b->m_uniqueId);
    if (x > y) std::swap(x, y);
    return (static_cast<std::uint64_t>(x) << 32) | y;
}

Vec3 toVec(const btVector3& v) { return {double(v.x()), double(v.y()), double(v.z())}; }

struct Record {
    const Proxy* first = nullptr;  ///< lower unique id
    const Proxy* second = nullptr;
    const btCollisionShape* shapeFirst = nullptr;
    const btCollisionShape* shapeSecond = nullptr;
    btTransform transformFirst;
    btTransform transformSecond;
    PairTriangles triangles;
};

template <typename F>
struct LeafVisitor : btDbvt::ICollide {
    explicit LeafVisitor(F f) : fn(std::move(f)) {}
    using btDbvt::ICollide::Process;
    void Process(const btDbvtNode* leaf) override { fn(static_cast<Proxy*>(leaf->data)); }
    F fn;
};
template <typename F>
LeafVisitor<F> visitLeaves(F f) {
    return LeafVisitor<F>(std::move(f));
}

template <typename F>
struct LeafPairVisitor : btDbvt::ICollide {
    explicit LeafPairVisitor(F f) : fn(std::move(f)) {}
    using btDbvt::ICollide::Process;
    void Process(const btDbvtNode* a, const btDbvtNode* b) override {
        fn(static_cast<Proxy*>(a->data), static_cast<Proxy*>(b->data));
    }
    F fn;
};
template <typename F>
LeafPairVisitor<F> visitLeafPairs(F f) {
    return LeafPairVisitor<F>(std::move(f));
}

}  // namespace

struct CullideBroadphase::Impl {
    Settings settings;
    CullerFactory factory;
    std::unique_ptr<Culler> culler;
    double margin = 0.0;
    bool shrinkFailed = false;  ///< recreating the culler with a smaller margin failed once: not tried again

    btOverlappingPairCache* cache = nullptr;
    bool ownsCache = false;

    btDbvt trees[2];  ///< kMovingTree, kRestingTree: the object level (leaves fattened like btDbvtBroadphase's)
    btAlignedObjectArray<const btDbvtNode*> rayStack;
    std::vector<Proxy*> proxies;
    int nextUid = 0;
    std::uint64_t nextKey = 0;
    std::uint64_t frame = 0;

    std::unordered_map<const btCollisionShape*, std::weak_ptr<bullet::ShapeTriangles>> shapeCache;
    /// Content hashes of the shapes seen this frame (cleared every frame: bounded, and shapes may come and go).
    std::unordered_map<const btCollisionShape*, std::uint64_t> hashThisFrame;
    std::unordered_map<std::uint64_t, Record> records;

    /// Ghost pairs: AABBs within this distance (btDbvtBroadphase pairs fattened leaves, gDbvtMargin = 0.05;
    /// btKinematicCharacterController sweeps only against its ghost's pairs and relies on that slack).
    btScalar ghostMargin = btScalar(0.1);
    bool deepPenetrationFallback = true;
    /// Hulls and compounds against triangle meshes go through the culler's levels (see trianglesConsumed).
    bool convexMeshCulling = false;
    std::vector<Proxy*> ghosts;  ///< proxies of ghost objects (eager pairing)

    CullideFrameStats stats;
    std::size_t rejectedTotal = 0;
    bool cullerFailureReported = false;

    // Per-frame scratch (members to reuse allocations).
    std::vector<Object> objects;
    std::vector<Proxy*> objectProxy;
    std::vector<bullet::MarginEntry> marginEntries;
    /// Object-level pairs of the last frame (carried over where both leaves rest) and of this one.
    std::vector<std::pair<Proxy*, Proxy*>> lastObjectPairs, objectPairsNow;
    bool incremental = false;  ///< this frame carried pairs over (collectObjectPairs)
    std::vector<Proxy*> destroyed;  ///< destroyed since the last frame, freed by forgetDestroyed
    const btOverlapFilterCallback* lastCallback = nullptr;
    bool lastConvexMeshCulling = false;
    std::map<std::pair<int, int>, std::size_t> lastFilterCounts;
    std::vector<std::pair<Proxy*, Proxy*>> candidates;  ///< object-level pairs whose triangles are read: culled
    std::vector<ObjectIndexPair> candidateIndices;
    Result result;
    /// The pairs the cache must hold after this frame (repeats allowed).
    struct Wanted {
        Proxy* a;
        Proxy* b;
    };
    std::vector<Wanted> desired;
    std::map<std::pair<int, int>, std::size_t> filterCounts;  ///< static objects per (group, mask)
    std::vector<std::uint8_t> inCache;  ///< per pair of the cache before the sync: still desired
    std::vector<std::pair<btBroadphaseProxy*, btBroadphaseProxy*>> toRemove;

    Impl(const Settings& s, btOverlappingPairCache* pairCache, CullerFactory f) : settings(s), factory(std::move(f)) {
        if (!factory) factory = [](const Settings& cs) { return createGpuCuller(cs); };
        const std::string error = settings.validate();
        if (!error.empty()) throw std::invalid_argument("cullide::CullideBroadphase: invalid settings: " + error);
        if (pairCache != nullptr) {
            cache = pairCache;
        } else {
            void* mem = btAlignedAlloc(sizeof(btHashedOverlappingPairCache), 16);
            cache = new (mem) btHashedOverlappingPairCache();
            ownsCache = true;
        }
        try {
            makeCuller(settings.margin > 0.0 ? settings.margin : kDefaultMargin);
        } catch (...) {
            releaseCache();
            throw;
        }
    }

    ~Impl() {
        for (Proxy* p : proxies) delete p;
        proxies.clear();
        forgetDestroyed();
        releaseCache();
    }

    void releaseCache() {
        if (ownsCache && cache != nullptr) {
            cache->~btOverlappingPairCache();
            btAlignedFree(cache);
        }
        cache = nullptr;
    }

    /// Replaces the culler by one with margin d; on failure (throws) the current culler stays as it was.
    void makeCuller(double d) {
        Settings s = settings;
        s.margin = d;
        // Bullet's triangle routines are the exact stage here: the culler hands over its surviving candidates.
        s.exactTriangles = false;
        std::unique_ptr<Culler> made = factory(s);
        if (!made) throw std::runtime_error("cullide::CullideBroadphase: the culler factory returned nothing");
        culler = std::move(made);
        margin = culler->settings().margin;
    }

    /// Keeps the culler's margin at least `required`, and not much more: a margin twice what the scene needs
    /// multiplies the within-margin triangle pairs the exact stage must test (the culler is recreated, with some
    /// headroom after the first frame so a changing scene does not recreate it every frame).
    void ensureMargin(double required) {
        if (required <= margin && margin <= settings.margin) return;  // the application asked for this margin
        if (required <= margin && shrinkFailed) return;  // a smaller culler could not be made: keep the sound one
        // The first frame sets it to exactly what the scene needs (the constructor's culler has a generic one).
        if (required <= margin && required >= 0.5 * margin && !(frame <= 1 && required < margin)) return;
        // Before the first frame: exactly what the scene needs; later with headroom, so a growing scene does not
        // recreate the culler every frame.
        makeCuller(std::max(settings.margin, (frame > 1 ? 1.25 : 1.0) * required));
    }

    // ---- proxies ----

    void reject(Proxy* p, const char* where, const std::string& why) {
        ++rejectedTotal;
        removeFromTree(p);
        p->valid = false;
        if (p->reported) return;
        p->reported = true;
        const btCollisionObject* obj = objectOf(p);
        std::fprintf(stderr,
                     "cullide::CullideBroadphase: %s: collision object %p (proxy %d, shape type %d) rejected: %s. "
                     "It gets no pairs until this is fixed; every other object is unaffected. "
                     "(Reported once per object; getRejectedCount() counts every occurrence.)\n",
                     where, static_cast<const void*>(obj), p->m_uniqueId, p->shapeType, why.c_str());
    }

    static std::string boxText(const btVector3& mn, const btVector3& mx) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "non-finite AABB [%g %g %g] - [%g %g %g]", double(mn.x()), double(mn.y()),
                      double(mn.z()), double(mx.x()), double(mx.y()), double(mx.z()));
        return buf;
    }

    void removeFromTree(Proxy* p) {
        if (p->leaf != nullptr) trees[p->treeId].remove(p->leaf);
        p->leaf = nullptr;
        p->treeId = kNoTree;
    }

    /// Moves a leaf to the other tree with the same (fattened) volume: the pairs found with it stay the same.
    void moveLeaf(Proxy* p, int id) {
        const btDbvtVolume volume = p->leaf->volume;
        trees[p->treeId].remove(p->leaf);
        p->leaf = trees[id].insert(volume, p);
        p->treeId = id;
    }

    /// Inserts or updates the proxy's leaf, fattened by kTreeMargin when the box leaves it (as btDbvtBroadphase). A
    /// leaf that moves goes to the moving tree and counts as moved in the next frame.
    void placeInTree(Proxy* p) {
        btDbvtVolume volume = btDbvtVolume::FromMM(p->m_aabbMin, p->m_aabbMax);
        if (p->leaf == nullptr) {
            p->leaf = trees[kMovingTree].insert(volume, p);
            p->treeId = kMovingTree;
            p->movedFrame = frame + 1;
            return;
        }
        if (p->leaf->volume.Contain(volume)) return;  // within its fattened leaf: nothing moves
        if (p->treeId != kMovingTree) moveLeaf(p, kMovingTree);
        trees[kMovingTree].update(p->leaf, volume, kTreeMargin);
        p->movedFrame = frame + 1;
    }

    /// Calls f(proxy) for every leaf of both trees whose volume overlaps `volume`.
    template <typename F>
    void forLeavesIn(const btDbvtVolume& volume, F f) {
        auto visitor = visitLeaves(std::move(f));
        for (btDbvt& t : trees)
            if (t.m_root != nullptr) t.collideTV(t.m_root, volume, visitor);
    }

    static bool isGhost(const Proxy* p) {
        const btCollisionObject* obj = objectOf(p);
        return obj != nullptr && (obj->getInternalType() & btCollisionObject::CO_GHOST_OBJECT) != 0;
    }
    static bool isStatic(const Proxy* p) {
        const btCollisionObject* obj = objectOf(p);
        return obj != nullptr && obj->isStaticObject();
    }
    static bool isInfinite(const Proxy* p) {
        const btCollisionObject* obj = objectOf(p);
        const int type = obj != nullptr && obj->getCollisionShape() != nullptr
                             ? obj->getCollisionShape()->getShapeType()
                             : p->shapeType;
        if (btBroadphaseProxy::isInfinite(type)) return true;
        for (int a = 0; a < 3; ++a)
            if (std::fabs(double(p->m_aabbMin[a])) > kInfiniteCoordinate ||
                std::fabs(double(p->m_aabbMax[a])) > kInfiniteCoordinate)
                return true;
        return false;
    }

    btDbvtVolume ghostVolume(const Proxy* ghost) const {
        const btVector3 g(ghostMargin, ghostMargin, ghostMargin);
        return btDbvtVolume::FromMM(ghost->m_aabbMin - g, ghost->m_aabbMax + g);
    }

    /// Ghost objects keep Bullet's semantics (pairs = AABB overlaps, filters only; Bullet creates ghosts with the
    /// static flag, so no static-static rule here) and, like btDbvtBroadphase, get new pairs at once.
    void addGhostPairs(Proxy* ghost) {
        forLeavesIn(ghostVolume(ghost), [&](Proxy* q) {
            if (q == ghost || !q->valid || !boxesOverlap(ghost, q, ghostMargin)) return;
            cache->addOverlappingPair(ghost, q);
        });
    }

    btBroadphaseProxy* createProxy(const btVector3& mn, const btVector3& mx, int shapeType, void* userPtr, int group,
                                   int mask) {
        auto* p = new Proxy(mn, mx, userPtr, group, mask, shapeType);
        p->m_uniqueId = ++nextUid;
        p->key = ++nextKey;
        p->slot = proxies.size();
        proxies.push_back(p);
        if (!finiteBox(mn, mx)) {
            if (isGhost(p)) ghosts.push_back(p);
            reject(p, "createProxy", boxText(mn, mx));
            return p;
        }
        placeInTree(p);
        if (isGhost(p)) {
            ghosts.push_back(p);
            addGhostPairs(p);
        } else {
            pairWithGhosts(p);
        }
        return p;
    }

    /// btDbvtBroadphase updates pairs in setAabb: a ghost sees an object entering at once.
    void pairWithGhosts(Proxy* p) {
        for (Proxy* g : ghosts)
            if (g->valid && boxesOverlap(g, p, ghostMargin)) cache->addOverlappingPair(g, p);
    }

    void destroyProxy(btBroadphaseProxy* abs, btDispatcher* dispatcher) {
        auto* p = static_cast<Proxy*>(abs);
        cache->removeOverlappingPairsContainingProxy(p, dispatcher);
        removeFromTree(p);
        ghosts.erase(std::remove(ghosts.begin(), ghosts.end(), p), ghosts.end());
        Proxy* last = proxies.back();
        proxies[p->slot] = last;
        last->slot = p->slot;
        proxies.pop_back();
        for (auto it = records.begin(); it != records.end();) {
            if (it->second.first == p || it->second.second == p)
                it = records.erase(it);
            else
                ++it;
        }
        // Freed at the next frame, once last frame's pairs have forgotten it (one pass for all destroyed proxies).
        p->role = Role::Invalid;
        destroyed.push_back(p);
    }

    void setAabb(btBroadphaseProxy* abs, const btVector3& mn, const btVector3& mx) {
        auto* p = static_cast<Proxy*>(abs);
        p->m_aabbMin = mn;
        p->m_aabbMax = mx;
        if (!finiteBox(mn, mx)) {
            reject(p, "setAabb", boxText(mn, mx));
            return;
        }
        p->valid = true;
        placeInTree(p);
        if (isGhost(p))
            addGhostPairs(p);
        else if (!ghosts.empty())
            pairWithGhosts(p);
    }

    // ---- geometry ----

    /// A shape's content hash, computed once per frame however many proxies share the shape.
    std::uint64_t sourceHashThisFrame(const btCollisionShape* shape) {
        const auto [it, added] = hashThisFrame.emplace(shape, 0);
        if (added) it->second = bullet::sourceHashOf(shape);
        return it->second;
    }

    std::shared_ptr<bullet::ShapeTriangles> geometryFor(Proxy* p, const btCollisionShape* shape) {
        if (shape == nullptr || bullet::geometryKindOf(shape) == bullet::GeometryKind::None) {
            p->geometry.reset();
            p->worldValid = false;
            return nullptr;
        }
        const std::uint64_t hash = sourceHashThisFrame(shape);
        if (p->geometry && bullet::stillMatches(*p->geometry, shape, hash)) return p->geometry;
        p->worldValid = false;
        auto it = shapeCache.find(shape);
        if (it != shapeCache.end()) {
            if (auto shared = it->second.lock(); shared && bullet::stillMatches(*shared, shape, hash)) {
                p->geometry = shared;
                return shared;
            }
        }
        auto built = bullet::buildShapeTriangles(shape, hash);
        if (built)
            shapeCache[shape] = built;
        else
            shapeCache.erase(shape);
        p->geometry = built;
        return built;
    }

    /// A btTransform as the culler's Transform. World vertices are transformPoint(toTransform(t), local vertex)
    /// everywhere (the culler for moving objects, updateWorld below for static ones and the broadphase's own
    /// triangle test), so both sides see bit-identical triangles.
    static Transform toTransform(const btTransform& t) {
        Transform out;
        const btMatrix3x3& basis = t.getBasis();
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) out.linear(r, c) = double(basis[r][c]);
            out.translation[r] = double(t.getOrigin()[r]);
        }
        return out;
    }

    void updateWorld(Proxy* p, const btTransform& t) {
        const bullet::ShapeTriangles& g = *p->geometry;
        if (p->worldValid && p->worldFrom == t && p->world.vertices.size() == g.local.vertices.size()) return;
        // worldValid is cleared whenever the geometry changes: a valid world mesh only needs new vertices.
        if (!p->worldValid || p->world.triangles.size() != g.triangles.size()) p->world.triangles = g.triangles;
        p->world.vertices.resize(g.local.vertices.size());
        const Transform toWorld = toTransform(t);  // the culler's own mapping: the same vertices as it builds
        for (std::size_t i = 0; i < g.local.vertices.size(); ++i)
            p->world.vertices[i] = transformPoint(toWorld, g.local.vertices[i]);
        p->worldFrom = t;
        p->worldValid = true;
        ++p->version;
    }

    // ---- the frame ----

    /// Every proxy's role and geometry kind this frame. A change of either counts as a move (its pairs are found
    /// again); a leaf that has not moved for kSettleFrames goes to the resting tree, one that moved to the moving one.
    void classify() {
        for (Proxy* p : proxies) {
            p->cullIndex = kNotCulled;
            p->pairsWithStatics = false;
            if (!p->valid)
                p->role = Role::Invalid;
            else if (isInfinite(p))
                p->role = Role::Infinite;
            else if (isGhost(p))
                p->role = Role::Ghost;
            else if (isStatic(p))
                p->role = Role::Static;
            else
                p->role = Role::Dynamic;
            const btCollisionObject* obj = objectOf(p);
            const btCollisionShape* shape = obj != nullptr ? obj->getCollisionShape() : nullptr;
            p->kind = bullet::geometryKindOf(shape);
            p->convex = shape != nullptr && shape->isConvex();
            if (p->role != p->lastRole || p->kind != p->lastKind) p->movedFrame = frame;
            p->lastRole = p->role;
            p->lastKind = p->kind;
            if (p->leaf == nullptr) continue;
            const bool moving = frame - std::min(frame, p->movedFrame) < kSettleFrames;
            if (moving != (p->treeId == kMovingTree)) moveLeaf(p, moving ? kMovingTree : kRestingTree);
        }
    }

    /// Whether static objects can pair with each other. Bullet's broadphases pair static objects like any others:
    /// only the filter (group/mask, the pair cache's overlap filter callback) decides, and the static flag does not
    /// (btDiscreteDynamicsWorld::addRigidBody gives static bodies the StaticFilter group and a mask without it:
    /// that is why dynamics worlds have no static-static pairs, while a btCollisionWorld of plain, static-flagged
    /// btCollisionObjects has them). With an overlap filter callback (it may admit anything) or a pair cache of
    /// unknown kind, every static object may.
    void markStaticsPairingStatics() {
        auto* hashed = dynamic_cast<btHashedOverlappingPairCache*>(cache);
        const bool anything = hashed == nullptr || hashed->getOverlapFilterCallback() != nullptr;
        filterCounts.clear();
        for (const Proxy* p : proxies)
            if (p->role == Role::Static) ++filterCounts[{p->m_collisionFilterGroup, p->m_collisionFilterMask}];
        for (Proxy* p : proxies) {
            if (p->role != Role::Static) continue;
            p->pairsWithStatics = anything;
            for (const auto& [filter, count] : filterCounts) {
                if (p->pairsWithStatics) break;
                const bool self =
                    filter.first == p->m_collisionFilterGroup && filter.second == p->m_collisionFilterMask;
                p->pairsWithStatics = (count > 1 || !self) && (p->m_collisionFilterGroup & filter.second) != 0 &&
                                      (filter.first & p->m_collisionFilterMask) != 0;
            }
        }
    }

    static bool pairable(const Proxy* p) { return p->role == Role::Dynamic || p->role == Role::Static; }

    /// The object level may pair a and b: both pairable, and two static objects only where both filters admit
    /// static partners (markStaticsPairingStatics). The pair cache's filter decides the rest.
    static bool mayPair(const Proxy* a, const Proxy* b) {
        if (!pairable(a) || !pairable(b)) return false;
        return !(a->role == Role::Static && b->role == Role::Static) || (a->pairsWithStatics && b->pairsWithStatics);
    }

    /// The object level: pairs of overlapping tree leaves (fattened boxes, as btDbvtBroadphase pairs them) that the
    /// pair cache's filter admits, static objects with each other only where their filters allow it
    /// (markStaticsPairingStatics). Incremental, like btDbvtBroadphase: only leaves that moved this frame (or whose
    /// role or kind changed) are searched for, against both trees; a pair of two leaves that did not move is last
    /// frame's verdict, unchanged. When what decides pairs changed (filters of static objects, the overlap filter
    /// callback, the culling policy), every pair is searched again. Pairs whose narrow phase reads triangles become
    /// culling candidates; every other pair goes to Bullet's algorithms as it is.
    void collectObjectPairs() {
        objectPairsNow.clear();
        // A carried pair that skips the culler is already in the pair cache: the sync keeps it (keptAsCarried).
        auto consider = [&](Proxy* a, Proxy* b, bool carried) {
            if (!mayPair(a, b) || !cache->needsBroadphaseCollision(a, b)) return;
            ++stats.objectPairs;
            objectPairsNow.emplace_back(a, b);
            if (culled(a, b))
                candidates.emplace_back(a, b);
            else if (!carried)
                addDesired(a, b);
        };
        incremental = pairRulesUnchanged();
        if (incremental) {
            for (const auto& [a, b] : lastObjectPairs)
                if (!moved(a) && !moved(b)) consider(a, b, true);
            stats.carriedPairs = objectPairsNow.size();
            for (Proxy* p : proxies) {
                if (p->leaf == nullptr || !moved(p) || !pairable(p)) continue;
                forLeavesIn(p->leaf->volume, [&](Proxy* q) {
                    if (q == p || (moved(q) && q->m_uniqueId < p->m_uniqueId)) return;  // once per pair
                    consider(p, q, false);
                });
            }
        } else {
            auto visitor = visitLeafPairs([&](Proxy* a, Proxy* b) { consider(a, b, false); });
            btDbvt& moving = trees[kMovingTree];
            btDbvt& resting = trees[kRestingTree];
            moving.collideTTpersistentStack(moving.m_root, moving.m_root, visitor);
            moving.collideTTpersistentStack(moving.m_root, resting.m_root, visitor);
            resting.collideTTpersistentStack(resting.m_root, resting.m_root, visitor);
        }
        lastObjectPairs.swap(objectPairsNow);
    }

    bool moved(const Proxy* p) const { return p->movedFrame == frame; }

    /// Drops destroyed proxies from last frame's pairs and frees them.
    void forgetDestroyed() {
        if (destroyed.empty()) return;
        for (Proxy* p : destroyed) p->treeId = kDestroyed;
        lastObjectPairs.erase(std::remove_if(lastObjectPairs.begin(), lastObjectPairs.end(),
                                             [](const std::pair<Proxy*, Proxy*>& pair) {
                                                 return pair.first->treeId == kDestroyed ||
                                                        pair.second->treeId == kDestroyed;
                                             }),
                              lastObjectPairs.end());
        for (Proxy* p : destroyed) delete p;
        destroyed.clear();
    }

    /// Whether the pair goes through the culler (its triangles are read, or the culler decides it).
    bool culled(const Proxy* a, const Proxy* b) const {
        return bullet::trianglesConsumed(a->kind, b->kind, convexMeshCulling) ||
               bullet::prunedByCuller(a->kind, a->convex, b->kind, b->convex);
    }

    /// A pair of the cache that this frame carried over without the culler (neither leaf moved, nothing that decides
    /// pairs changed): it was wanted last frame and still is, so the sync leaves it alone.
    bool keptAsCarried(const btBroadphaseProxy* p0, const btBroadphaseProxy* p1) const {
        const auto* a = static_cast<const Proxy*>(p0);
        const auto* b = static_cast<const Proxy*>(p1);
        return incremental && mayPair(a, b) && !moved(a) && !moved(b) && !culled(a, b);
    }

    /// Whether last frame's pairs of leaves that did not move still hold: the same static filters, overlap filter
    /// callback and culling policy (records what it compares for the next frame).
    bool pairRulesUnchanged() {
        auto* hashed = dynamic_cast<btHashedOverlappingPairCache*>(cache);
        const btOverlapFilterCallback* callback = hashed != nullptr ? hashed->getOverlapFilterCallback() : nullptr;
        const bool same = frame > 1 && hashed != nullptr && callback == lastCallback &&
                          convexMeshCulling == lastConvexMeshCulling && filterCounts == lastFilterCounts;
        lastCallback = callback;
        lastConvexMeshCulling = convexMeshCulling;
        lastFilterCounts = filterCounts;
        return same;
    }

    /// The culling frame: the objects of the candidate pairs (meshes in their own frame with their transform, or
    /// world-space for static ones, kept between steps), the candidate pairs by object index, and what the margin
    /// rule needs of each object.
    void buildCullFrame() {
        objects.clear();
        objectProxy.clear();
        marginEntries.clear();
        candidateIndices.clear();
        for (auto& [a, b] : candidates) {
            for (Proxy* p : {a, b})
                if (p->cullIndex == kNotCulled) addCulled(p);
            candidateIndices.emplace_back(std::min(a->cullIndex, b->cullIndex), std::max(a->cullIndex, b->cullIndex));
        }
        std::sort(candidateIndices.begin(), candidateIndices.end());
        candidateIndices.erase(std::unique(candidateIndices.begin(), candidateIndices.end()), candidateIndices.end());
        stats.culledObjects = objects.size();
        stats.culledPairs = candidateIndices.size();
        for (const Proxy* p : proxies)
            if (p->role == Role::Static && p->cullIndex == kNotCulled) ++stats.staticObjectsSkipped;
    }

    void addCulled(Proxy* p) {
        const btCollisionObject* obj = objectOf(p);
        const btCollisionShape* shape = obj->getCollisionShape();
        Object o;
        bullet::MarginEntry entry;
        entry.kind = p->kind;
        // Every pair has a moving member, or two static ones whose filters admit each other.
        entry.moving = p->role == Role::Dynamic || p->pairsWithStatics;
        entry.motionDisc = double(shape->getAngularMotionDisc());
        if (geometryFor(p, shape)) {
            if (p->role == Role::Static) {
                // World-space, kept between steps with the culler's static cache (staticKey below).
                updateWorld(p, obj->getWorldTransform());
                o.mesh = &p->world;
            } else {
                // The shape's local mesh and this step's transform: the culler maps the vertices only if the
                // object comes near another one (the same arithmetic as updateWorld, see toTransform).
                p->toWorld = toTransform(obj->getWorldTransform());
                o.mesh = &p->geometry->local;
                o.transform = &p->toWorld;
                for (int k = 0; k < 3; ++k)
                    entry.coordinate = std::max({entry.coordinate, std::fabs(double(p->m_aabbMin[k])),
                                                 std::fabs(double(p->m_aabbMax[k]))});
            }
            ++stats.meshObjects;
            stats.triangles += p->geometry->triangles.size();
        } else {
            entry.kind = bullet::GeometryKind::None;
            o.box.min = toVec(p->m_aabbMin);
            o.box.max = toVec(p->m_aabbMax);
        }
        switch (entry.kind) {
            case bullet::GeometryKind::GImpactMesh:
            case bullet::GeometryKind::Compound: entry.margin = double(bullet::triangleMarginOf(shape)); break;
            default: entry.margin = double(shape->getMargin()); break;
        }
        if (p->role == Role::Static) {
            o.staticKey = p->key;
            o.version = p->version;
        }
        p->cullIndex = static_cast<std::uint32_t>(objects.size());
        objects.push_back(o);
        objectProxy.push_back(p);
        marginEntries.push_back(entry);
    }

    bullet::BreakingRule breakingRule(btDispatcher* dispatcher) const {
        const auto* collisionDispatcher = dynamic_cast<const btCollisionDispatcher*>(dispatcher);
        bullet::BreakingRule rule;
        rule.threshold = double(gContactBreakingThreshold);
        rule.relative = collisionDispatcher == nullptr ||
                        (collisionDispatcher->getDispatcherFlags() &
                         btCollisionDispatcher::CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD) != 0;
        rule.epsilon = double(std::numeric_limits<btScalar>::epsilon());
        return rule;
    }

    /// Without a working culler: every candidate pair, no triangles (the dispatcher runs Bullet's full algorithms).
    void candidatesWithoutCulling() {
        for (const auto& [a, b] : candidates) addDesired(a, b);
    }

    /// The culler over the candidate pairs; false when it failed (reported once).
    bool runCuller() {
        result.clear();
        if (candidateIndices.empty()) return true;
        try {
            culler->run(objects, candidateIndices, result);
            return true;
        } catch (const std::exception& e) {
            reportCullerFailure(e);
            return false;
        }
    }

    void reportCullerFailure(const std::exception& e) {
        if (cullerFailureReported) return;
        cullerFailureReported = true;
        std::fprintf(stderr,
                     "cullide::CullideBroadphase: the culler failed (%s); AABB pairs are used for such frames "
                     "(reported once)\n",
                     e.what());
    }

    void addDesired(Proxy* a, Proxy* b) {
        if (a->m_uniqueId > b->m_uniqueId) std::swap(a, b);
        desired.push_back({a, b});
    }

    /// The box of triangle t of a world mesh, computed once per makeRecord side (stamped cache).
    struct TriangleBoxes {
        std::vector<Aabb> boxes;
        std::vector<std::uint32_t> stamp;
        std::uint32_t current = 0;
        void begin(std::size_t triangles) {
            if (boxes.size() < triangles) {
                boxes.resize(triangles);
                stamp.resize(triangles, 0);
            }
            if (++current == 0) {  // wrapped: forget every stamp
                std::fill(stamp.begin(), stamp.end(), 0);
                current = 1;
            }
        }
        const Aabb& of(const TriangleMesh& m, std::uint32_t t) {
            if (stamp[t] != current) {
                Aabb b;
                for (std::uint32_t v : m.triangles[t]) b.grow(m.vertices[v]);
                boxes[t] = b;
                stamp[t] = current;
            }
            return boxes[t];
        }
    };
    TriangleBoxes boxesA, boxesB;

    /// GImpact-GImpact: of the culler's triangle pairs, those whose triangle boxes, grown by the shapes' margins,
    /// overlap, as Bullet's (part, index) pairs in record orientation, sorted. A pair whose grown boxes are apart is
    /// farther apart than both margins; the clip method can then make a contact only from a point of one triangle
    /// more than both margins behind the other's plane: inside the other mesh where it is thicker than that, i.e.
    /// deep interpenetration, which the fallback hands to Bullet's full algorithm. Returns whether the meshes
    /// intersect (some kept pair shares a point; tested only with the fallback on). The dispatcher keeps, of these
    /// pairs, those that Bullet's own BVH search would also produce.
    bool nearGImpactPairs(const Proxy& pa, const Proxy& pb, const ObjectPair& op, bool flip,
                          std::vector<BulletTrianglePair>& out) {
        const double ma = double(bullet::triangleMarginOf(objectOf(&pa)->getCollisionShape()));
        const double mb = double(bullet::triangleMarginOf(objectOf(&pb)->getCollisionShape()));
        const TriangleMesh& wa = pa.world;
        const TriangleMesh& wb = pb.world;
        boxesA.begin(wa.triangles.size());
        boxesB.begin(wb.triangles.size());
        bool intersecting = false;
        out.reserve(op.triangles.size());
        for (const TrianglePair& tp : op.triangles) {
            const Aabb& a = boxesA.of(wa, tp.a);
            const Aabb& b = boxesB.of(wb, tp.b);
            if (!a.inflated(ma).overlaps(b.inflated(mb))) continue;
            if (deepPenetrationFallback && !intersecting && a.overlaps(b)) {  // triangles that meet have meeting boxes
                const TriangleIndices& x = wa.triangles[tp.a];
                const TriangleIndices& y = wb.triangles[tp.b];
                intersecting = trianglesIntersect(wa.vertices[x[0]], wa.vertices[x[1]], wa.vertices[x[2]],
                                                  wb.vertices[y[0]], wb.vertices[y[1]], wb.vertices[y[2]]);
            }
            const BulletTriangle ta = pa.geometry->refs[tp.a];
            const BulletTriangle tb = pb.geometry->refs[tp.b];
            out.push_back(flip ? BulletTrianglePair{tb, ta} : BulletTrianglePair{ta, tb});
        }
        const auto order = [](const BulletTrianglePair& x, const BulletTrianglePair& y) {
            if (x.a.part != y.a.part) return x.a.part < y.a.part;
            if (x.b.part != y.b.part) return x.b.part < y.b.part;
            if (x.a.index != y.a.index) return x.a.index < y.a.index;
            return x.b.index < y.b.index;
        };
        if (!std::is_sorted(out.begin(), out.end(), order)) std::sort(out.begin(), out.end(), order);
        return intersecting;
    }

    void makeRecord(Proxy* pa, Proxy* pb, const ObjectPair& op) {
        using bullet::GeometryKind;
        const GeometryKind ka = pa->geometry ? pa->geometry->kind : GeometryKind::None;
        const GeometryKind kb = pb->geometry ? pb->geometry->kind : GeometryKind::None;
        const bool gimpactPair = ka == GeometryKind::GImpactMesh && kb == GeometryKind::GImpactMesh;
        // Convex hulls, compounds of convex children and GImpact meshes against triangle meshes: the mesh's
        // surviving triangles.
        auto convexSide = [](GeometryKind k) {
            return k == GeometryKind::ConvexHull || k == GeometryKind::Compound || k == GeometryKind::GImpactMesh;
        };
        const bool convexMesh = (convexSide(ka) && kb == GeometryKind::TriangleMesh) ||
                                (ka == GeometryKind::TriangleMesh && convexSide(kb));
        if (!gimpactPair && !convexMesh) return;
        // Record orientation: first = lower unique id; culler orientation: a = pa.
        const bool flip = pa->m_uniqueId > pb->m_uniqueId;
        const Proxy* first = flip ? pb : pa;
        const Proxy* second = flip ? pa : pb;
        Record rec;
        rec.first = first;
        rec.second = second;
        rec.shapeFirst = objectOf(first)->getCollisionShape();
        rec.shapeSecond = objectOf(second)->getCollisionShape();
        rec.transformFirst = objectOf(first)->getWorldTransform();
        rec.transformSecond = objectOf(second)->getWorldTransform();
        if (gimpactPair) {
            updateWorld(pa, objectOf(pa)->getWorldTransform());  // no-op where it is up to date (static objects)
            updateWorld(pb, objectOf(pb)->getWorldTransform());
            const bool intersecting = nearGImpactPairs(*pa, *pb, op, flip, rec.triangles.pairs);
            stats.trianglePairs += rec.triangles.pairs.size();
            rec.triangles.interpenetrating = intersecting;
            if (intersecting) ++stats.interpenetratingPairs;
        } else {
            const bool meshIsA = ka == GeometryKind::TriangleMesh;
            const bullet::ShapeTriangles& mesh = meshIsA ? *pa->geometry : *pb->geometry;
            std::vector<std::uint32_t> tris;
            tris.reserve(op.triangles.size());
            for (const TrianglePair& tp : op.triangles) tris.push_back(meshIsA ? tp.a : tp.b);
            std::sort(tris.begin(), tris.end());
            tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
            std::vector<std::pair<BulletTriangle, std::uint32_t>> ordered;
            ordered.reserve(tris.size());
            for (std::uint32_t t : tris) ordered.emplace_back(mesh.refs[t], t);
            std::sort(ordered.begin(), ordered.end(),
                      [](const auto& x, const auto& y) { return x.first < y.first; });
            for (const auto& [ref, t] : ordered) {
                rec.triangles.meshTriangles.push_back(ref);
                for (std::uint32_t v : mesh.triangles[t]) rec.triangles.meshTriangleVertices.push_back(mesh.vertices[v]);
            }
            stats.trianglePairs += rec.triangles.meshTriangles.size();
        }
        records[pairKey(pa, pb)] = std::move(rec);
    }

    /// Candidate pairs the culler kept (with their surviving triangles for the dispatcher); the others are provably
    /// farther apart than the margin: no pair. Objects the culler rejected lose every pair this frame.
    void collectCullerPairs() {
        for (const ObjectDiagnostic& d : result.rejected) {
            Proxy* p = objectProxy[d.object];
            p->role = Role::Invalid;  // no infinite or ghost pairs either
            ++stats.rejectedObjects;
            ++rejectedTotal;
            if (!p->reported) {
                p->reported = true;
                std::fprintf(stderr,
                             "cullide::CullideBroadphase: collision object %p (proxy %d) rejected by the culler: %s. "
                             "It gets no pairs; every other object is unaffected. (Reported once per object.)\n",
                             static_cast<const void*>(objectOf(p)), p->m_uniqueId, d.message.c_str());
            }
        }
        if (!result.rejected.empty())
            desired.erase(std::remove_if(desired.begin(), desired.end(),
                                         [](const Wanted& w) {
                                             return w.a->role == Role::Invalid || w.b->role == Role::Invalid;
                                         }),
                          desired.end());
        for (const ObjectPair& op : result.pairs) {
            Proxy* pa = objectProxy[op.a];
            Proxy* pb = objectProxy[op.b];
            addDesired(pa, pb);
            ++stats.cullerPairs;
            if (op.hasTriangles) makeRecord(pa, pb, op);
        }
        stats.prunedPairs = stats.culledPairs - std::min(stats.culledPairs, result.pairs.size());
    }

    /// Planes pair by a half-space test, other infinite boxes by plain AABB overlap. Never rasterised.
    bool infiniteTouches(const Proxy* inf, const Proxy* q) const {
        const btCollisionObject* obj = objectOf(inf);
        const btCollisionShape* shape = obj != nullptr ? obj->getCollisionShape() : nullptr;
        if (shape == nullptr || shape->getShapeType() != STATIC_PLANE_PROXYTYPE || q->role == Role::Infinite)
            return boxesOverlap(inf, q);
        const auto* plane = static_cast<const btStaticPlaneShape*>(shape);
        const btTransform& t = obj->getWorldTransform();
        const btVector3 n = t.getBasis() * plane->getPlaneNormal();
        const btVector3 onPlane = t * (plane->getPlaneNormal() * plane->getPlaneConstant());
        const double c = double(n.dot(onPlane));
        const btVector3 centre = (q->m_aabbMin + q->m_aabbMax) * btScalar(0.5);
        const btVector3 half = (q->m_aabbMax - q->m_aabbMin) * btScalar(0.5);
        const double lowest = double(n.dot(centre)) - (std::fabs(double(n.x())) * double(half.x()) +
                                                       std::fabs(double(n.y())) * double(half.y()) +
                                                       std::fabs(double(n.z())) * double(half.z()));
        return lowest <= c + double(plane->getMargin()) + margin;
    }

    void collectInfinitePairs() {
        for (Proxy* inf : proxies) {
            if (inf->role != Role::Infinite) continue;
            ++stats.infiniteObjects;
            for (Proxy* q : proxies) {
                if (q == inf || q->role == Role::Invalid || q->role == Role::Ghost) continue;
                if (q->role == Role::Infinite && q->m_uniqueId < inf->m_uniqueId) continue;  // once per pair
                if (!infiniteTouches(inf, q)) continue;
                addDesired(inf, q);
                ++stats.infinitePairs;
            }
        }
    }

    void collectGhostPairs() {
        for (Proxy* g : proxies) {
            if (g->role != Role::Ghost) continue;
            ++stats.ghostObjects;
            forLeavesIn(ghostVolume(g), [&](Proxy* q) {
                if (q == g || q->role == Role::Invalid || !boxesOverlap(g, q, ghostMargin)) return;
                if (q->role == Role::Ghost && q->m_uniqueId < g->m_uniqueId) return;  // once per pair
                addDesired(g, q);
                ++stats.ghostPairs;
            });
        }
    }

    /// Makes the pair cache hold exactly the wanted pairs that its filter admits: the pairs carried over without the
    /// culler (kept where they are, never looked up) and the desired ones (new object-level pairs, the culler's,
    /// planes', ghosts'). Each desired pair is looked up in the cache (a hash lookup) and marked where it already is;
    /// other pairs are removed (their algorithms freed through the dispatcher), missing ones added through the cache
    /// (filters, ghost pair callback) in the order they were collected (deterministic: the trees' order).
    void syncPairCache(btDispatcher* dispatcher) {
        const int before = cache->getNumOverlappingPairs();
        inCache.assign(static_cast<std::size_t>(before), 0);
        for (const Wanted& w : desired) {
            if (const btBroadphasePair* pair = cache->findPair(w.a, w.b)) {
                const std::size_t index = static_cast<std::size_t>(pair - &cache->getOverlappingPairArray()[0]);
                if (index < inCache.size() && cache->needsBroadphaseCollision(w.a, w.b)) inCache[index] = 1;
                continue;
            }
            const int count = cache->getNumOverlappingPairs();
            cache->addOverlappingPair(w.a, w.b);
            if (cache->getNumOverlappingPairs() > count) ++stats.pairsAdded;
        }
        toRemove.clear();
        const btBroadphasePairArray& array = cache->getOverlappingPairArray();
        for (std::size_t i = 0; i < inCache.size(); ++i) {
            const btBroadphasePair& pair = array[static_cast<int>(i)];
            if (inCache[i]) continue;
            if (keptAsCarried(pair.m_pProxy0, pair.m_pProxy1) &&
                cache->needsBroadphaseCollision(pair.m_pProxy0, pair.m_pProxy1))
                continue;
            toRemove.emplace_back(pair.m_pProxy0, pair.m_pProxy1);
        }
        for (const auto& [p0, p1] : toRemove) cache->removeOverlappingPair(p0, p1, dispatcher);
        stats.pairsRemoved = toRemove.size();
        stats.pairs = static_cast<std::size_t>(cache->getNumOverlappingPairs());
    }

    void calculateOverlappingPairs(btDispatcher* dispatcher) {
        cullide::Timer total;
        ++frame;
        stats = CullideFrameStats{};
        forgetDestroyed();
        stats.proxies = proxies.size();
        hashThisFrame.clear();
        records.clear();
        desired.clear();
        candidates.clear();

        cullide::Timer build;
        classify();
        for (const Proxy* p : proxies)
            if (p->role == Role::Invalid) ++stats.rejectedObjects;
        markStaticsPairingStatics();
        collectObjectPairs();
        buildCullFrame();
        bool cullerUsable = !candidateIndices.empty();
        if (cullerUsable) {
            const double required = bullet::requiredCullingMargin(marginEntries, breakingRule(dispatcher));
            try {
                ensureMargin(required);
            } catch (const std::exception& e) {
                reportCullerFailure(e);
                // A culler that could not be made smaller is still sound; one whose margin is too small for this
                // scene is not: the candidates go to Bullet's full algorithms instead.
                cullerUsable = culler != nullptr && required <= margin;
                if (cullerUsable) shrinkFailed = true;
            }
        }
        stats.margin = margin;
        stats.buildMs = build.ms();

        cullide::Timer cull;
        if (cullerUsable) cullerUsable = runCuller();
        stats.cullMs = cull.ms();
        stats.culler = result.stats;
        for (const auto& list : result.pcsTriangles) stats.pcsTriangles += list.size();

        cullide::Timer sync;
        if (cullerUsable)
            collectCullerPairs();
        else
            candidatesWithoutCulling();
        collectInfinitePairs();
        collectGhostPairs();
        syncPairCache(dispatcher);
        stats.syncMs = sync.ms();
        stats.totalMs = total.ms();
    }

    const PairTriangles* trianglePairsFor(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                                          bool& swapped) const {
        swapped = false;
        if (records.empty() || w0 == nullptr || w1 == nullptr) return nullptr;
        const btCollisionObject* o0 = w0->getCollisionObject();
        const btCollisionObject* o1 = w1->getCollisionObject();
        if (o0 == nullptr || o1 == nullptr) return nullptr;
        // A child wrapper (compound algorithm, GImpact part) is trusted only on a compound's side of the record.
        const bool child0 = w0->getCollisionShape() != o0->getCollisionShape();
        const bool child1 = w1->getCollisionShape() != o1->getCollisionShape();
        const btBroadphaseProxy* p0 = o0->getBroadphaseHandle();
        const btBroadphaseProxy* p1 = o1->getBroadphaseHandle();
        if (p0 == nullptr || p1 == nullptr) return nullptr;
        const auto it = records.find(pairKey(p0, p1));
        if (it == records.end()) return nullptr;
        const Record& rec = it->second;
        if (rec.first == p0 && rec.second == p1)
            swapped = false;
        else if (rec.first == p1 && rec.second == p0)
            swapped = true;
        else
            return nullptr;
        const btCollisionShape* s0 = swapped ? rec.shapeSecond : rec.shapeFirst;
        const btCollisionShape* s1 = swapped ? rec.shapeFirst : rec.shapeSecond;
        const btTransform& t0 = swapped ? rec.transformSecond : rec.transformFirst;
        const btTransform& t1 = swapped ? rec.transformFirst : rec.transformSecond;
        // On a compound's side the compound algorithm's child wrappers may use the record: the mesh triangles kept
        // for the whole compound are a superset of those near any one child.
        auto compound = [](const btCollisionShape* s) { return s->getShapeType() == COMPOUND_SHAPE_PROXYTYPE; };
        if ((child0 && !compound(s0)) || (child1 && !compound(s1))) return nullptr;
        // Compare the objects' shapes and transforms (a child wrapper carries the child's).
        if (s0 != o0->getCollisionShape() || s1 != o1->getCollisionShape()) return nullptr;
        if (!(t0 == o0->getWorldTransform()) || !(t1 == o1->getWorldTransform())) return nullptr;  // moved since
        if (!child0 && !(t0 == w0->getWorldTransform())) return nullptr;
        if (!child1 && !(t1 == w1->getWorldTransform())) return nullptr;
        return &rec.triangles;
    }
};

CullideBroadphase::CullideBroadphase(detail::PrecisionChecked, const Settings& settings,
                                     btOverlappingPairCache* pairCache, CullerFactory factory)
    : m_impl(std::make_unique<Impl>(settings, pairCache, std::move(factory))) {}

CullideBroadphase::~CullideBroadphase() = default;

btBroadphaseProxy* CullideBroadphase::createProxy(const btVector3& aabbMin, const btVector3& aabbMax, int shapeType,
                                                  void* userPtr, int collisionFilterGroup, int collisionFilterMask,
                                                  btDispatcher* /*dispatcher*/) {
    return m_impl->createProxy(aabbMin, aabbMax, shapeType, userPtr, collisionFilterGroup, collisionFilterMask);
}

void CullideBroadphase::destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) {
    m_impl->destroyProxy(proxy, dispatcher);
}

void CullideBroadphase::setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                                btDispatcher* /*dispatcher*/) {
    m_impl->setAabb(proxy, aabbMin, aabbMax);
}

void CullideBroadphase::getAabb(btBroadphaseProxy* proxy, btVector3& aabbMin, btVector3& aabbMax) const {
    aabbMin = proxy->m_aabbMin;
    aabbMax = proxy->m_aabbMax;
}

void CullideBroadphase::rayTest(const btVector3& rayFrom, const btVector3& rayTo, btBroadphaseRayCallback& rayCallback,
                                const btVector3& aabbMin, const btVector3& aabbMax) {
    auto visitor = visitLeaves([&](Proxy* p) { rayCallback.process(p); });
    for (btDbvt& tree : m_impl->trees)
        tree.rayTestInternal(tree.m_root, rayFrom, rayTo, rayCallback.m_rayDirectionInverse, rayCallback.m_signs,
                             rayCallback.m_lambda_max, aabbMin, aabbMax, m_impl->rayStack, visitor);
}

void CullideBroadphase::aabbTest(const btVector3& aabbMin, const btVector3& aabbMax,
                                 btBroadphaseAabbCallback& callback) {
    m_impl->forLeavesIn(btDbvtVolume::FromMM(aabbMin, aabbMax), [&](Proxy* p) { callback.process(p); });
}

void CullideBroadphase::calculateOverlappingPairs(btDispatcher* dispatcher) {
    m_impl->calculateOverlappingPairs(dispatcher);
}

btOverlappingPairCache* CullideBroadphase::getOverlappingPairCache() { return m_impl->cache; }
const btOverlappingPairCache* CullideBroadphase::getOverlappingPairCache() const { return m_impl->cache; }

void CullideBroadphase::getBroadphaseAabb(btVector3& aabbMin, btVector3& aabbMax) const {
    bool any = false;
    for (const btDbvt& tree : m_impl->trees) {
        if (tree.m_root == nullptr) continue;
        if (!any) {
            aabbMin = tree.m_root->volume.Mins();
            aabbMax = tree.m_root->volume.Maxs();
        } else {
            aabbMin.setMin(tree.m_root->volume.Mins());
            aabbMax.setMax(tree.m_root->volume.Maxs());
        }
        any = true;
    }
    if (!any) {
        aabbMin.setValue(0, 0, 0);
        aabbMax.setValue(0, 0, 0);
    }
}

void CullideBroadphase::resetPool(btDispatcher* /*dispatcher*/) {
    if (!m_impl->proxies.empty()) return;
    for (btDbvt& tree : m_impl->trees) tree.clear();
    m_impl->forgetDestroyed();
    m_impl->lastObjectPairs.clear();
    m_impl->records.clear();
    m_impl->shapeCache.clear();
    m_impl->nextUid = 0;
}

void CullideBroadphase::printStats() {
    const CullideFrameStats& s = m_impl->stats;
    std::printf(
        "CullideBroadphase: %zu proxies, %zu object pairs (%zu culled, %zu pruned), %zu culled objects (%zu meshes, %zu triangles, %zu static skipped), %zu infinite, "
        "%zu ghosts, %zu rejected; pairs %zu (culler %zu, infinite %zu, ghost %zu; +%zu -%zu), %zu triangle pairs, "
        "margin %.4g; build %.3f ms, cull %.3f ms, sync %.3f ms, total %.3f ms\n",
        s.proxies, s.objectPairs, s.culledPairs, s.prunedPairs, s.culledObjects, s.meshObjects, s.triangles, s.staticObjectsSkipped, s.infiniteObjects,
        s.ghostObjects, s.rejectedObjects, s.pairs, s.cullerPairs, s.infinitePairs, s.ghostPairs, s.pairsAdded,
        s.pairsRemoved, s.trianglePairs, s.margin, s.buildMs, s.cullMs, s.syncMs, s.totalMs);
}

const PairTriangles* CullideBroadphase::trianglePairsFor(const btCollisionObjectWrapper* body0Wrap,
                                                         const btCollisionObjectWrapper* body1Wrap,
                                                         bool& swapped) const {
    return m_impl->trianglePairsFor(body0Wrap, body1Wrap, swapped);
}

void CullideBroadphase::invalidateShape(const btCollisionShape* shape) {
    m_impl->shapeCache.erase(shape);
    for (Proxy* p : m_impl->proxies) {
        if (p->geometry && p->geometry->shape == shape) {
            p->geometry.reset();
            p->worldValid = false;
        }
    }
}

void CullideBroadphase::setGhostPairMargin(btScalar margin) { m_impl->ghostMargin = btMax(margin, btScalar(0)); }
btScalar CullideBroadphase::getGhostPairMargin() const { return m_impl->ghostMargin; }
void CullideBroadphase::setDeepPenetrationFallback(bool enable) { m_impl->deepPenetrationFallback = enable; }
bool CullideBroadphase::getDeepPenetrationFallback() const { return m_impl->deepPenetrationFallback; }

void CullideBroadphase::setConvexMeshCulling(bool enable) { m_impl->convexMeshCulling = enable; }
bool CullideBroadphase::getConvexMeshCulling() const { return m_impl->convexMeshCulling; }

const CullideFrameStats& CullideBroadphase::getLastFrameStats() const { return m_impl->stats; }
std::size_t CullideBroadphase::getRejectedCount() const { return m_impl->rejectedTotal; }
double CullideBroadphase::getCullingMargin() const { return m_impl->margin; }
const Settings& CullideBroadphase::getSettings() const { return m_impl->settings; }

}  // namespace cullide
