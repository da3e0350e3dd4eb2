#include "cullide_bullet/CullideBroadphase.h"
#include "cullide/Timer.h"

#include "CullingPolicy.h"
#include "ShapeGeometry.h"
#include "cullide/Result.h"
#include "cullide/TriangleTest.h"

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>

namespace cullide {

int detail::bulletScalarSizeOfLibrary() noexcept { return static_cast<int>(sizeof(btScalar)); }

namespace {

/// AABB coordinates beyond this are "infinite" (btStaticPlaneShape reports +-BT_LARGE_FLOAT = 1e18 in float builds):
/// such objects are never handed to the culler; their pairs go to Bullet's algorithms as they are.
constexpr double kInfiniteCoordinate = 1e15;
/// A GImpact pair found interpenetrating (deep-penetration fallback on) runs Bullet's full algorithm, which reads
/// nothing the culler computes: it skips the culler for this many following steps (recorded as interpenetrating:
/// Bullet's full algorithm, Bullet's contacts), then is culled again. Interpenetration persists over steps in piles and
/// fractures; a pair that separated costs at most this many steps of Bullet's full algorithm, never a contact.
constexpr std::uint64_t kPenetrationRecheck = 4;
/// Used for the constructor's culler when Settings::margin is 0 (it must exist to report a missing GL device at
/// construction); the first frame recreates it with exactly the margin the scene needs (see ensureMargin).
constexpr double kDefaultMargin = 0.12;

btCollisionObject* objectOf(const btBroadphaseProxy* p) { return static_cast<btCollisionObject*>(p->m_clientObject); }
const btCollisionShape* shapeOf(const btBroadphaseProxy* p) {
    const btCollisionObject* o = objectOf(p);
    return o != nullptr ? o->getCollisionShape() : nullptr;
}

bool finiteBox(const btVector3& mn, const btVector3& mx) {
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(mn[a]) || !std::isfinite(mx[a])) return false;
    return true;
}

bool infiniteBox(const btBroadphaseProxy* p) {
    for (int a = 0; a < 3; ++a)
        if (std::fabs(double(p->m_aabbMin[a])) > kInfiniteCoordinate ||
            std::fabs(double(p->m_aabbMax[a])) > kInfiniteCoordinate)
            return true;
    return false;
}

/// Where a proxy with a non-finite AABB waits in the object level's tree: a point beyond every finite box Bullet
/// makes (planes reach BT_LARGE_FLOAT), so it keeps the tree's volumes finite and meets no valid object.
btVector3 parkedPoint() {
    const btScalar far = std::numeric_limits<btScalar>::max() / btScalar(4);
    return btVector3(far, far, far);
}

std::uint64_t pairKey(const btBroadphaseProxy* a, const btBroadphaseProxy* b) {
    auto x = static_cast<std::uint32_t>(a->m_uniqueId);
    auto y = static_cast<std::uint32_t>(b->m_uniqueId);
    if (x > y) std::swap(x, y);
    return (static_cast<std::uint64_t>(x) << 32) | y;
}

Vec3 toVec(const btVector3& v) { return {double(v.x()), double(v.y()), double(v.z())}; }

/// A btTransform as the culler's Transform. World vertices are transformPoint(toTransform(t), local vertex)
/// everywhere (the culler for moving objects, worldMeshOf for static ones and the broadphase's own triangle test),
/// so both sides see bit-identical triangles.
Transform toTransform(const btTransform& t) {
    Transform out;
    const btMatrix3x3& basis = t.getBasis();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) out.linear(r, c) = double(basis[r][c]);
        out.translation[r] = double(t.getOrigin()[r]);
    }
    return out;
}

/// What the broadphase keeps of an object that took part in a culled pair: its triangle geometry (shared per
/// shape), the transform that places it for the culler, and a world-space copy (static objects, kept between
/// steps with the culler's static cache; and pairs whose triangles the broadphase itself tests, built on demand).
struct CulledObject {
    std::uint64_t key = 0;  ///< staticKey for the culler (never reused)
    std::shared_ptr<bullet::ShapeTriangles> geometry;
    Transform toWorld;
    TriangleMesh world;
    btTransform worldFrom;
    bool worldValid = false;
    std::uint64_t version = 0;
    // This frame.
    std::uint64_t frame = 0;     ///< the last frame it entered the culling frame
    std::uint32_t cullIndex = 0;  ///< its index in that frame's objects
    bool reported = false;       ///< its rejection by the culler was reported
};

/// The surviving triangles of one object pair, handed from the broadphase to the dispatcher (see trianglePairsFor):
/// valid for the shapes and transforms the pair had when the broadphase computed it.
struct Record {
    const btBroadphaseProxy* first = nullptr;  ///< lower unique id
    const btBroadphaseProxy* second = nullptr;
    const btCollisionShape* shapeFirst = nullptr;
    const btCollisionShape* shapeSecond = nullptr;
    btTransform transformFirst;
    btTransform transformSecond;
    PairTriangles triangles;
};

/// Record orientation (first = lower unique id) of the culler's pair (pa, pb), shapes and transforms as now.
Record recordFor(const btBroadphaseProxy* pa, const btBroadphaseProxy* pb) {
    const bool flip = pa->m_uniqueId > pb->m_uniqueId;
    Record rec;
    rec.first = flip ? pb : pa;
    rec.second = flip ? pa : pb;
    rec.shapeFirst = shapeOf(rec.first);
    rec.shapeSecond = shapeOf(rec.second);
    rec.transformFirst = objectOf(rec.first)->getWorldTransform();
    rec.transformSecond = objectOf(rec.second)->getWorldTransform();
    return rec;
}

/// The box of triangle t of a world mesh, computed once per record side (stamped cache).
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

}  // namespace

/// The object level is Bullet's own btDbvtBroadphase (incremental trees, fattened leaves, lazy pair removal, ghost
/// objects, planes, filters, the overlap filter callback, ray and box queries): the pair cache holds exactly the
/// pairs Bullet's default pipeline would hand to its narrow phase. What is added:
/// - a guard for non-finite AABBs (they would poison the tree's volumes for every object): such a proxy is parked
///   far away with a filter mask of 0 and its pairs removed until it gets a finite box again;
/// - the culling of pairs whose narrow phase reads triangles (collectCandidates, buildCullFrame, runCuller): the
///   culler's verdict and surviving triangles are recorded per pair for CullideCollisionDispatcher (recordVerdicts). A pair the culler proves farther
///   apart than the margin stays in the cache, as in Bullet, and its narrow phase reports nothing.
struct CullideBroadphase::Impl {
    // ---- the object level ----
    std::unique_ptr<btDbvtBroadphase> objectLevel;
    std::size_t proxyCount = 0;
    /// Proxies with a non-finite AABB, with the filter mask they had: restored when the AABB is finite again.
    std::unordered_map<const btBroadphaseProxy*, int> parked;
    std::size_t rejectedTotal = 0;

    // ---- the culler ----
    Settings settings;
    CullerFactory factory;
    std::unique_ptr<Culler> culler;
    double margin = 0.0;
    bool shrinkFailed = false;  ///< recreating the culler with a smaller margin failed once: not tried again
    bool cullerFailureReported = false;
    bool deepPenetrationFallback = true;
    /// Hulls and compounds against triangle meshes go through the culler's levels (see trianglesConsumed).
    bool convexMeshCulling = false;
    bool gimpactPairCulling = false;

    // ---- the culling frame: objects of culled pairs ----
    std::unordered_map<const btBroadphaseProxy*, CulledObject> culledObjects;
    std::unordered_map<const btCollisionShape*, std::weak_ptr<bullet::ShapeTriangles>> shapeCache;
    /// Content hashes of the shapes seen this frame (cleared every frame: bounded, and shapes may come and go).
    std::unordered_map<const btCollisionShape*, std::uint64_t> hashThisFrame;
    std::uint64_t nextKey = 0;
    std::uint64_t frame = 0;
    std::vector<std::pair<btBroadphaseProxy*, btBroadphaseProxy*>> candidates;  ///< cache pairs that are culled
    std::vector<Object> objects;
    std::vector<btBroadphaseProxy*> objectProxy;
    std::vector<bullet::MarginEntry> marginEntries;
    std::vector<ObjectIndexPair> candidateIndices;
    Result result;

    // ---- the hand-off to the dispatcher ----
    std::unordered_map<std::uint64_t, Record> records;
    /// Pairs found interpenetrating: the last frame in which they skip the culler (kPenetrationRecheck).
    std::unordered_map<std::uint64_t, std::uint64_t> penetratingUntil;
    TriangleBoxes boxesA, boxesB;

    CullideFrameStats stats;

    Impl(const Settings& s, btOverlappingPairCache* pairCache, CullerFactory f) : settings(s), factory(std::move(f)) {
        if (!factory) factory = [](const Settings& cs) { return createGpuCuller(cs); };
        const std::string error = settings.validate();
        if (!error.empty()) throw std::invalid_argument("cullide::CullideBroadphase: invalid settings: " + error);
        makeCuller(settings.margin > 0.0 ? settings.margin : kDefaultMargin);
        objectLevel.reset(new btDbvtBroadphase(pairCache));  // btDbvtBroadphase's aligned operator new
    }

    btOverlappingPairCache* cache() const { return objectLevel->getOverlappingPairCache(); }

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
        if (required <= margin && required >= 0.5 * margin && !(frame <= 1 && required < margin)) return;
        makeCuller(std::max(settings.margin, (frame > 1 ? 1.25 : 1.0) * required));
    }

    // ---- proxies: Bullet's, with non-finite boxes parked ----

    static std::string boxText(const btVector3& mn, const btVector3& mx) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "non-finite AABB [%g %g %g] - [%g %g %g]", double(mn.x()), double(mn.y()),
                      double(mn.z()), double(mx.x()), double(mx.y()), double(mx.z()));
        return buf;
    }

    /// Parks `p` (non-finite AABB): no pairs, a mask of 0 so that none are made, reported once per parking.
    void park(btBroadphaseProxy* p, const char* where, const std::string& why, btDispatcher* dispatcher) {
        ++rejectedTotal;
        const auto [it, added] = parked.emplace(p, p->m_collisionFilterMask);
        const btVector3 point = parkedPoint();
        objectLevel->setAabb(p, point, point, dispatcher);
        if (!added) return;
        p->m_collisionFilterMask = 0;
        cache()->removeOverlappingPairsContainingProxy(p, dispatcher);
        std::fprintf(stderr,
                     "cullide::CullideBroadphase: %s: collision object %p (proxy %d) rejected: %s. It gets no pairs "
                     "until its AABB is finite again; every other object is unaffected. (Reported each time it is "
                     "parked; getRejectedCount() counts every call.)\n",
                     where, static_cast<const void*>(objectOf(p)), p->m_uniqueId, why.c_str());
    }

    void unpark(btBroadphaseProxy* p) {
        const auto it = parked.find(p);
        if (it == parked.end()) return;
        p->m_collisionFilterMask = it->second;
        parked.erase(it);
    }

    btBroadphaseProxy* createProxy(const btVector3& mn, const btVector3& mx, int shapeType, void* userPtr, int group,
                                   int mask, btDispatcher* dispatcher) {
        const bool finite = finiteBox(mn, mx);
        const btVector3 point = parkedPoint();
        btBroadphaseProxy* p = objectLevel->createProxy(finite ? mn : point, finite ? mx : point, shapeType, userPtr,
                                                        group, mask, dispatcher);
        ++proxyCount;
        if (!finite) park(p, "createProxy", boxText(mn, mx), dispatcher);
        return p;
    }

    void setAabb(btBroadphaseProxy* p, const btVector3& mn, const btVector3& mx, btDispatcher* dispatcher) {
        if (!finiteBox(mn, mx)) {
            park(p, "setAabb", boxText(mn, mx), dispatcher);
            return;
        }
        unpark(p);
        objectLevel->setAabb(p, mn, mx, dispatcher);
    }

    void destroyProxy(btBroadphaseProxy* p, btDispatcher* dispatcher) {
        unpark(p);
        culledObjects.erase(p);
        for (auto it = records.begin(); it != records.end();)
            it = it->second.first == p || it->second.second == p ? records.erase(it) : std::next(it);
        objectLevel->destroyProxy(p, dispatcher);
        --proxyCount;
    }

    // ---- geometry of culled objects ----

    /// A shape's content hash, computed once per frame however many proxies share the shape.
    std::uint64_t sourceHashThisFrame(const btCollisionShape* shape) {
        const auto [it, added] = hashThisFrame.emplace(shape, 0);
        if (added) it->second = bullet::sourceHashOf(shape);
        return it->second;
    }

    std::shared_ptr<bullet::ShapeTriangles> geometryFor(CulledObject& c, const btCollisionShape* shape) {
        if (shape == nullptr || bullet::geometryKindOf(shape) == bullet::GeometryKind::None) {
            c.geometry.reset();
            c.worldValid = false;
            return nullptr;
        }
        const std::uint64_t hash = sourceHashThisFrame(shape);
        if (c.geometry && bullet::stillMatches(*c.geometry, shape, hash)) return c.geometry;
        c.worldValid = false;
        auto it = shapeCache.find(shape);
        if (it != shapeCache.end()) {
            if (auto shared = it->second.lock(); shared && bullet::stillMatches(*shared, shape, hash)) {
                c.geometry = shared;
                return shared;
            }
        }
        auto built = bullet::buildShapeTriangles(shape, hash);
        if (built)
            shapeCache[shape] = built;
        else
            shapeCache.erase(shape);
        c.geometry = built;
        return built;
    }

    /// The object's world-space triangles at transform t (the culler's own mapping, see toTransform).
    static void updateWorld(CulledObject& c, const btTransform& t) {
        const bullet::ShapeTriangles& g = *c.geometry;
        if (c.worldValid && c.worldFrom == t && c.world.vertices.size() == g.local.vertices.size()) return;
        // worldValid is cleared whenever the geometry changes: a valid world mesh only needs new vertices.
        if (!c.worldValid || c.world.triangles.size() != g.triangles.size()) c.world.triangles = g.triangles;
        c.world.vertices.resize(g.local.vertices.size());
        const Transform toWorld = toTransform(t);
        for (std::size_t i = 0; i < g.local.vertices.size(); ++i)
            c.world.vertices[i] = transformPoint(toWorld, g.local.vertices[i]);
        c.worldFrom = t;
        c.worldValid = true;
        ++c.version;
    }

    // ---- the frame ----

    /// Whether the pair goes through the culler: its narrow phase reads triangles, or the culler decides it
    /// (CullingPolicy); never for parked objects or infinite boxes (planes, huge AABBs: Bullet's algorithms).
    bool culled(const btBroadphaseProxy* a, const btBroadphaseProxy* b) const {
        const btCollisionShape* sa = shapeOf(a);
        const btCollisionShape* sb = shapeOf(b);
        if (sa == nullptr || sb == nullptr) return false;
        // Every culled pair has a GImpact shape, or a triangle mesh with convex-mesh culling on: most pairs stop here.
        auto mayBe = [&](const btCollisionShape* s) {
            const int type = s->getShapeType();
            return type == GIMPACT_SHAPE_PROXYTYPE || (convexMeshCulling && bullet::isTriangleMeshType(type));
        };
        if (!mayBe(sa) && !mayBe(sb)) return false;
        const bullet::GeometryKind ka = bullet::geometryKindOf(sa);
        const bullet::GeometryKind kb = bullet::geometryKindOf(sb);
        if (!bullet::trianglesConsumed(ka, kb, convexMeshCulling, gimpactPairCulling) &&
            !bullet::prunedByCuller(ka, sa->isConvex(), kb, sb->isConvex()))
            return false;
        return parked.count(a) == 0 && parked.count(b) == 0 && !infiniteBox(a) && !infiniteBox(b);
    }

    /// The pairs of the cache that go through the culler this frame; pairs the dispatcher will not process
    /// (needsCollision: both asleep, collide-with exclusions) cost nothing.
    void collectCandidates(btDispatcher* dispatcher) {
        candidates.clear();
        btOverlappingPairCache* pairs = cache();
        const int n = pairs->getNumOverlappingPairs();
        if (n == 0) return;
        btBroadphasePair* array = pairs->getOverlappingPairArrayPtr();
        for (int i = 0; i < n; ++i) {
            btBroadphaseProxy* a = array[i].m_pProxy0;
            btBroadphaseProxy* b = array[i].m_pProxy1;
            if (a == nullptr || b == nullptr || !culled(a, b)) continue;
            if (dispatcher != nullptr && !dispatcher->needsCollision(objectOf(a), objectOf(b))) continue;
            if (recentlyPenetrating(a, b)) {
                // Recorded as interpenetrating: the dispatcher runs Bullet's full algorithm for it.
                Record rec = recordFor(a, b);
                rec.triangles.interpenetrating = true;
                records[pairKey(a, b)] = std::move(rec);
                ++stats.penetratingSkipped;
                continue;
            }
            candidates.emplace_back(a, b);
        }
    }

    bool recentlyPenetrating(const btBroadphaseProxy* a, const btBroadphaseProxy* b) const {
        if (penetratingUntil.empty()) return false;
        const auto it = penetratingUntil.find(pairKey(a, b));
        return it != penetratingUntil.end() && frame <= it->second;
    }

    /// Forgets pairs whose skipping ended (bounded by the pairs that interpenetrated in the last few steps).
    void expirePenetrating() {
        for (auto it = penetratingUntil.begin(); it != penetratingUntil.end();)
            it = it->second < frame ? penetratingUntil.erase(it) : std::next(it);
    }

    /// The culling frame: the objects of the candidate pairs (meshes in their own frame with their transform, or
    /// world-space for static ones, kept between steps), the candidate pairs by object index, and what the margin
    /// rule needs of each object.
    void buildCullFrame() {
        objects.clear();
        objectProxy.clear();
        marginEntries.clear();
        candidateIndices.clear();
        for (const auto& [a, b] : candidates) {
            CulledObject& ca = enter(a);
            CulledObject& cb = enter(b);
            if (objectOf(a)->isStaticObject() && objectOf(b)->isStaticObject()) {
                // Two static objects whose filters admit each other: both count as moving for the margin rule.
                marginEntries[ca.cullIndex].moving = marginEntries[cb.cullIndex].moving = true;
            }
            candidateIndices.emplace_back(std::min(ca.cullIndex, cb.cullIndex), std::max(ca.cullIndex, cb.cullIndex));
        }
        std::sort(candidateIndices.begin(), candidateIndices.end());
        stats.culledObjects = objects.size();
        stats.culledPairs = candidateIndices.size();
    }

    /// The object of proxy p in this frame's culling frame (added on first use).
    CulledObject& enter(btBroadphaseProxy* p) {
        CulledObject& c = culledObjects[p];
        if (c.key == 0) c.key = ++nextKey;
        if (c.frame == frame) return c;
        c.frame = frame;
        c.cullIndex = static_cast<std::uint32_t>(objects.size());
        const btCollisionObject* obj = objectOf(p);
        const btCollisionShape* shape = obj->getCollisionShape();
        const bool isStatic = obj->isStaticObject();
        Object o;
        bullet::MarginEntry entry;
        entry.kind = bullet::geometryKindOf(shape);
        entry.moving = !isStatic;
        entry.motionDisc = double(shape->getAngularMotionDisc());
        if (geometryFor(c, shape)) {
            if (isStatic) {
                // World-space, kept between steps with the culler's static cache (staticKey below).
                updateWorld(c, obj->getWorldTransform());
                o.mesh = &c.world;
                o.staticKey = c.key;
                o.version = c.version;
            } else {
                // The shape's local mesh and this step's transform: the culler maps the vertices only if the
                // object comes near another one (the same arithmetic as updateWorld, see toTransform).
                c.toWorld = toTransform(obj->getWorldTransform());
                o.mesh = &c.geometry->local;
                o.transform = &c.toWorld;
                for (int k = 0; k < 3; ++k)
                    entry.coordinate = std::max({entry.coordinate, std::fabs(double(p->m_aabbMin[k])),
                                                 std::fabs(double(p->m_aabbMax[k]))});
            }
            ++stats.meshObjects;
            stats.triangles += c.geometry->triangles.size();
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
        objects.push_back(o);
        objectProxy.push_back(p);
        marginEntries.push_back(entry);
        return c;
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

    /// A culler whose margin covers this frame's pairs; false when there is none (the pairs then get no record:
    /// the dispatcher runs Bullet's full algorithms for them).
    bool cullerReady(btDispatcher* dispatcher) {
        const double required = bullet::requiredCullingMargin(marginEntries, breakingRule(dispatcher));
        try {
            ensureMargin(required);
            return true;
        } catch (const std::exception& e) {
            reportCullerFailure(e);
            // A culler that could not be made smaller is still sound; one whose margin is too small is not.
            const bool usable = culler != nullptr && required <= margin;
            if (usable) shrinkFailed = true;
            return usable;
        }
    }

    /// The culler over the candidate pairs; false when it failed (reported once).
    bool runCuller() {
        result.clear();
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
                     "cullide::CullideBroadphase: the culler failed (%s); Bullet's full algorithms run for such "
                     "frames (reported once)\n",
                     e.what());
    }

    // ---- records: the hand-off to the dispatcher ----

    /// GImpact-GImpact: of the culler's triangle pairs, those whose triangle boxes, grown by the shapes' margins,
    /// overlap, as Bullet's (part, index) pairs in record orientation, sorted. A pair whose grown boxes are apart is
    /// farther apart than both margins; the clip method can then make a contact only from a point of one triangle
    /// more than both margins behind the other's plane: inside the other mesh where it is thicker than that, i.e.
    /// deep interpenetration, which the fallback hands to Bullet's full algorithm. Returns whether the meshes
    /// intersect (some kept pair shares a point; tested only with the fallback on), and then no list: the dispatcher
    /// runs Bullet's full algorithm. Otherwise the dispatcher keeps, of these pairs, those that Bullet's own BVH
    /// search would also produce.
    bool nearGImpactPairs(const btBroadphaseProxy* pa, const CulledObject& ca, const btBroadphaseProxy* pb,
                          const CulledObject& cb, const ObjectPair& op, bool flip,
                          std::vector<BulletTrianglePair>& out) {
        const double ma = double(bullet::triangleMarginOf(shapeOf(pa)));
        const double mb = double(bullet::triangleMarginOf(shapeOf(pb)));
        const TriangleMesh& wa = ca.world;
        const TriangleMesh& wb = cb.world;
        boxesA.begin(wa.triangles.size());
        boxesB.begin(wb.triangles.size());
        out.reserve(op.triangles.size());
        for (const TrianglePair& tp : op.triangles) {
            const Aabb& a = boxesA.of(wa, tp.a);
            const Aabb& b = boxesB.of(wb, tp.b);
            if (!a.inflated(ma).overlaps(b.inflated(mb))) continue;
            if (deepPenetrationFallback && a.overlaps(b)) {  // triangles that meet have meeting boxes
                const TriangleIndices& x = wa.triangles[tp.a];
                const TriangleIndices& y = wb.triangles[tp.b];
                if (trianglesIntersect(wa.vertices[x[0]], wa.vertices[x[1]], wa.vertices[x[2]], wb.vertices[y[0]],
                                       wb.vertices[y[1]], wb.vertices[y[2]])) {
                    out.clear();  // Bullet's full algorithm runs for the pair: its list would not be read
                    return true;
                }
            }
            const BulletTriangle ta = ca.geometry->refs[tp.a];
            const BulletTriangle tb = cb.geometry->refs[tp.b];
            out.push_back(flip ? BulletTrianglePair{tb, ta} : BulletTrianglePair{ta, tb});
        }
        const auto order = [](const BulletTrianglePair& x, const BulletTrianglePair& y) {
            if (x.a.part != y.a.part) return x.a.part < y.a.part;
            if (x.b.part != y.b.part) return x.b.part < y.b.part;
            if (x.a.index != y.a.index) return x.a.index < y.a.index;
            return x.b.index < y.b.index;
        };
        if (!std::is_sorted(out.begin(), out.end(), order)) std::sort(out.begin(), out.end(), order);
        return false;
    }

    /// The mesh's surviving triangles of a convex/GImpact-vs-triangle-mesh pair, sorted as Bullet names them, with
    /// their mesh-local vertices.
    static void survivingMeshTriangles(const bullet::ShapeTriangles& mesh, bool meshIsA, const ObjectPair& op,
                                       PairTriangles& out) {
        std::vector<std::uint32_t> tris;
        tris.reserve(op.triangles.size());
        for (const TrianglePair& tp : op.triangles) tris.push_back(meshIsA ? tp.a : tp.b);
        std::sort(tris.begin(), tris.end());
        tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
        std::vector<std::pair<BulletTriangle, std::uint32_t>> ordered;
        ordered.reserve(tris.size());
        for (std::uint32_t t : tris) ordered.emplace_back(mesh.refs[t], t);
        std::sort(ordered.begin(), ordered.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
        for (const auto& [ref, t] : ordered) {
            out.meshTriangles.push_back(ref);
            for (std::uint32_t v : mesh.triangles[t]) out.meshTriangleVertices.push_back(mesh.vertices[v]);
        }
    }

    /// The record of a pair the culler kept with surviving triangles (GImpact-GImpact, or a convex or GImpact shape
    /// against a triangle mesh); other kept pairs get none (the dispatcher runs Bullet's algorithm for them).
    void recordKept(const ObjectPair& op) {
        using bullet::GeometryKind;
        btBroadphaseProxy* pa = objectProxy[op.a];
        btBroadphaseProxy* pb = objectProxy[op.b];
        CulledObject& ca = culledObjects[pa];
        CulledObject& cb = culledObjects[pb];
        const GeometryKind ka = ca.geometry ? ca.geometry->kind : GeometryKind::None;
        const GeometryKind kb = cb.geometry ? cb.geometry->kind : GeometryKind::None;
        const bool gimpactPair = ka == GeometryKind::GImpactMesh && kb == GeometryKind::GImpactMesh;
        auto convexSide = [](GeometryKind k) {
            return k == GeometryKind::ConvexHull || k == GeometryKind::Compound || k == GeometryKind::GImpactMesh;
        };
        const bool convexMesh = (convexSide(ka) && kb == GeometryKind::TriangleMesh) ||
                                (ka == GeometryKind::TriangleMesh && convexSide(kb));
        if (!op.hasTriangles || (!gimpactPair && !convexMesh)) return;
        Record rec = recordFor(pa, pb);
        if (gimpactPair) {
            updateWorld(ca, objectOf(pa)->getWorldTransform());  // no-op where it is up to date (static objects)
            updateWorld(cb, objectOf(pb)->getWorldTransform());
            const bool flip = rec.first != pa;
            rec.triangles.interpenetrating = nearGImpactPairs(pa, ca, pb, cb, op, flip, rec.triangles.pairs);
            stats.trianglePairs += rec.triangles.pairs.size();
            if (rec.triangles.interpenetrating) {
                ++stats.interpenetratingPairs;
                penetratingUntil[pairKey(pa, pb)] = frame + kPenetrationRecheck;
            }
        } else {
            const bool meshIsA = ka == GeometryKind::TriangleMesh;
            survivingMeshTriangles(meshIsA ? *ca.geometry : *cb.geometry, meshIsA, op, rec.triangles);
            stats.trianglePairs += rec.triangles.meshTriangles.size();
        }
        records[pairKey(pa, pb)] = std::move(rec);
    }

    void reportRejected(const ObjectDiagnostic& d) {
        btBroadphaseProxy* p = objectProxy[d.object];
        CulledObject& c = culledObjects[p];
        ++stats.rejectedObjects;
        ++rejectedTotal;
        if (c.reported) return;
        c.reported = true;
        std::fprintf(stderr,
                     "cullide::CullideBroadphase: collision object %p (proxy %d) rejected by the culler: %s. Its "
                     "culled pairs get no contacts; every other object is unaffected. (Reported once per object.)\n",
                     static_cast<const void*>(objectOf(p)), p->m_uniqueId, d.message.c_str());
    }

    /// Records of the culler's verdicts: kept pairs with their surviving triangles, and every candidate pair the
    /// culler did not keep (provably farther apart than the margin, or with an object it rejected) as pruned: the
    /// dispatcher makes no contact for it this step.
    void recordVerdicts() {
        for (const ObjectDiagnostic& d : result.rejected) reportRejected(d);
        std::vector<std::uint8_t> kept(candidateIndices.size(), 0);
        for (const ObjectPair& op : result.pairs) {
            const ObjectIndexPair key(std::min(op.a, op.b), std::max(op.a, op.b));
            const auto it = std::lower_bound(candidateIndices.begin(), candidateIndices.end(), key);
            if (it != candidateIndices.end() && *it == key) kept[std::size_t(it - candidateIndices.begin())] = 1;
            ++stats.cullerPairs;
            recordKept(op);
        }
        for (std::size_t i = 0; i < candidateIndices.size(); ++i) {
            if (kept[i]) continue;
            Record rec = recordFor(objectProxy[candidateIndices[i].first], objectProxy[candidateIndices[i].second]);
            rec.triangles.pruned = true;
            records[pairKey(rec.first, rec.second)] = std::move(rec);
            ++stats.prunedPairs;
        }
    }

    void calculateOverlappingPairs(btDispatcher* dispatcher) {
        cullide::Timer total;
        ++frame;
        stats = CullideFrameStats{};
        records.clear();
        hashThisFrame.clear();

        cullide::Timer objectTimer;
        objectLevel->calculateOverlappingPairs(dispatcher);
        stats.objectLevelMs = objectTimer.ms();
        stats.proxies = proxyCount;
        stats.objectPairs = static_cast<std::size_t>(cache()->getNumOverlappingPairs());
        stats.rejectedObjects = parked.size();

        cullide::Timer build;
        if (!deepPenetrationFallback) penetratingUntil.clear();
        expirePenetrating();
        collectCandidates(dispatcher);
        if (!candidates.empty()) {
            buildCullFrame();
            const bool ready = cullerReady(dispatcher);
            stats.buildMs = build.ms();
            cullide::Timer cull;
            const bool ran = ready && runCuller();
            stats.cullMs = cull.ms();
            stats.culler = result.stats;
            for (const auto& list : result.pcsTriangles) stats.pcsTriangles += list.size();
            cullide::Timer recordTimer;
            if (ran) recordVerdicts();
            stats.recordMs = recordTimer.ms();
        }
        stats.margin = margin;
        stats.totalMs = total.ms();
    }

    /// The record of the pair of the two wrapped objects, when it is still true: the same proxies, shapes and
    /// transforms as when it was made (a compound's child wrapper may use its compound's record).
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
                                                  btDispatcher* dispatcher) {
    return m_impl->createProxy(aabbMin, aabbMax, shapeType, userPtr, collisionFilterGroup, collisionFilterMask,
                               dispatcher);
}

void CullideBroadphase::destroyProxy(btBroadphaseProxy* proxy, btDispatcher* dispatcher) {
    m_impl->destroyProxy(proxy, dispatcher);
}

void CullideBroadphase::setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                                btDispatcher* dispatcher) {
    m_impl->setAabb(proxy, aabbMin, aabbMax, dispatcher);
}

void CullideBroadphase::getAabb(btBroadphaseProxy* proxy, btVector3& aabbMin, btVector3& aabbMax) const {
    m_impl->objectLevel->getAabb(proxy, aabbMin, aabbMax);
}

void CullideBroadphase::rayTest(const btVector3& rayFrom, const btVector3& rayTo, btBroadphaseRayCallback& rayCallback,
                                const btVector3& aabbMin, const btVector3& aabbMax) {
    m_impl->objectLevel->rayTest(rayFrom, rayTo, rayCallback, aabbMin, aabbMax);
}

void CullideBroadphase::aabbTest(const btVector3& aabbMin, const btVector3& aabbMax,
                                 btBroadphaseAabbCallback& callback) {
    m_impl->objectLevel->aabbTest(aabbMin, aabbMax, callback);
}

void CullideBroadphase::calculateOverlappingPairs(btDispatcher* dispatcher) {
    m_impl->calculateOverlappingPairs(dispatcher);
}

btOverlappingPairCache* CullideBroadphase::getOverlappingPairCache() { return m_impl->cache(); }
const btOverlappingPairCache* CullideBroadphase::getOverlappingPairCache() const { return m_impl->cache(); }

void CullideBroadphase::getBroadphaseAabb(btVector3& aabbMin, btVector3& aabbMax) const {
    m_impl->objectLevel->getBroadphaseAabb(aabbMin, aabbMax);
}

void CullideBroadphase::resetPool(btDispatcher* dispatcher) {
    m_impl->objectLevel->resetPool(dispatcher);
    if (m_impl->proxyCount != 0) return;
    m_impl->records.clear();
    m_impl->culledObjects.clear();
    m_impl->shapeCache.clear();
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

const PairTriangles* CullideBroadphase::trianglePairsFor(const btCollisionObjectWrapper* body0Wrap,
                                                         const btCollisionObjectWrapper* body1Wrap,
                                                         bool& swapped) const {
    return m_impl->trianglePairsFor(body0Wrap, body1Wrap, swapped);
}

void CullideBroadphase::invalidateShape(const btCollisionShape* shape) {
    m_impl->shapeCache.erase(shape);
    for (auto& [proxy, c] : m_impl->culledObjects) {
        if (c.geometry && c.geometry->shape == shape) {
            c.geometry.reset();
            c.worldValid = false;
        }
    }
}

void CullideBroadphase::setDeepPenetrationFallback(bool enable) { m_impl->deepPenetrationFallback = enable; }
bool CullideBroadphase::getDeepPenetrationFallback() const { return m_impl->deepPenetrationFallback; }

void CullideBroadphase::setConvexMeshCulling(bool enable) { m_impl->convexMeshCulling = enable; }
bool CullideBroadphase::getConvexMeshCulling() const { return m_impl->convexMeshCulling; }

void CullideBroadphase::setGImpactPairCulling(bool enable) { m_impl->gimpactPairCulling = enable; }
bool CullideBroadphase::getGImpactPairCulling() const { return m_impl->gimpactPairCulling; }

const CullideFrameStats& CullideBroadphase::getLastFrameStats() const { return m_impl->stats; }
std::size_t CullideBroadphase::getRejectedCount() const { return m_impl->rejectedTotal; }
double CullideBroadphase::getCullingMargin() const { return m_impl->margin; }
const Settings& CullideBroadphase::getSettings() const { return m_impl->settings; }

}  // namespace cullide
