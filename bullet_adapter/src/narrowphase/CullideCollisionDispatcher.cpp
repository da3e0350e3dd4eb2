#include "cullide_bullet/CullideCollisionDispatcher.h"
#include "narrowphase/AdapterAccess.h"
#include "narrowphase/ApartPairs.h"
#include "narrowphase/GImpactConvexContacts.h"
#include "narrowphase/GImpactLeafPairs.h"
#include "narrowphase/GImpactMeshContacts.h"
#include "narrowphase/GImpactPlaneContacts.h"
#include "broadphase/ShapeGeometry.h"
#include "narrowphase/ThreadedPairs.h"
#include "cullide/TaskPool.h"
#include "cullide/Timer.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionDispatch/btCollisionConfiguration.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btPoolAllocator.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>
#include <typeinfo>
#include <unordered_map>
#include <vector>

namespace cullide {
namespace detail {

/// The leaf node of each primitive of a GImpact box set (btGImpactQuantizedBvh), so a surviving triangle pair can be
/// tested exactly as Bullet's BVH traversal tests it. Entries are checked on every lookup (the leaf must still hold
/// the primitive) and rebuilt when a box set was rebuilt (updateBound after deforming) or its address reused; box
/// sets unused for kKeepDispatches dispatches (deleted shapes) are dropped.
class GImpactLeafIndex {
public:
    /// Called at the start of every dispatch: drops the entries of box sets no longer used.
    void beginDispatch() {
        ++m_epoch;
        for (auto it = m_leaves.begin(); it != m_leaves.end();) {
            if (it->second.lastUse + kKeepDispatches < m_epoch)
                it = m_leaves.erase(it);
            else
                ++it;
        }
    }
    /// The leaf node of each primitive of `set`, as last built (stable until the next beginDispatch): check an
    /// entry with `leafOf`.
    std::vector<int>& leavesOf(const btGImpactBoxSet& set) {
        Entry& e = m_leaves[&set];
        e.lastUse = m_epoch;
        return e.leaves;
    }
    /// The leaf of `prim` (rebuilding `leaves` once if it is stale), or -1 when the set has none.
    static int leafOf(const btGImpactBoxSet& set, std::vector<int>& leaves, int prim) {
        if (!holds(set, leaves, prim)) {
            rebuild(set, leaves);
            if (!holds(set, leaves, prim)) return -1;
        }
        return leaves[static_cast<std::size_t>(prim)];
    }

private:
    static constexpr std::uint64_t kKeepDispatches = 60;
    struct Entry {
        std::vector<int> leaves;
        std::uint64_t lastUse = 0;
    };

    static bool holds(const btGImpactBoxSet& set, const std::vector<int>& leaves, int prim) {
        if (prim < 0 || static_cast<std::size_t>(prim) >= leaves.size()) return false;
        const int node = leaves[static_cast<std::size_t>(prim)];
        return node >= 0 && node < set.getNodeCount() && set.isLeafNode(node) && set.getNodeData(node) == prim;
    }
    static void rebuild(const btGImpactBoxSet& set, std::vector<int>& leaves) {
        leaves.assign(static_cast<std::size_t>(std::max(set.getPrimitiveManager()->get_primitive_count(), 0)), -1);
        for (int node = 0; node < set.getNodeCount(); ++node) {
            if (!set.isLeafNode(node)) continue;
            const int prim = set.getNodeData(node);
            if (prim >= 0 && static_cast<std::size_t>(prim) < leaves.size()) leaves[static_cast<std::size_t>(prim)] = node;
        }
    }

    std::uint64_t m_epoch = 0;
    std::unordered_map<const btGImpactBoxSet*, Entry> m_leaves;
};

}  // namespace detail

namespace {

CullideCollisionDispatcher& cullideDispatcher(btDispatcher* d) { return *static_cast<CullideCollisionDispatcher*>(d); }

/// Whether the result is the world's own (btManifoldResult exactly), which drops every point beyond the manifold's
/// breaking threshold: what the adapter's paths rely on when they skip triangles out of that reach or read the
/// culler's. A result of another class may accept such points (btCollisionWorld::contactTest's
/// btBridgedManifoldResult checks no threshold; an application's own): Bullet's algorithm as it is then.
bool thresholdChecked(const btManifoldResult& result) { return typeid(result) == typeid(btManifoldResult); }

/// CULLIDE's surviving triangles for a pair (nullptr: not culled this step, Bullet's own algorithm must run) and
/// the dispatcher's statistics of the current step.
const PairTriangles* cullideTrianglesFor(btDispatcher* d, const btCollisionObjectWrapper* body0Wrap,
                                         const btCollisionObjectWrapper* body1Wrap, bool& swapped,
                                         CullideDispatchStats*& stats) {
    CullideCollisionDispatcher& dispatcher = cullideDispatcher(d);
    stats = &detail::AdapterAccess::currentStats(dispatcher);
    swapped = false;
    const CullideBroadphase* broadphase = dispatcher.getCullideBroadphase();
    if (broadphase == nullptr) return nullptr;
    return detail::AdapterAccess::trianglePairsFor(*broadphase, body0Wrap, body1Wrap, swapped);
}

/// A stand-in for a triangle mesh that enumerates only CULLIDE's surviving triangles (mesh-local vertices, Bullet's
/// part and triangle ids). Lives on the stack for one processCollision call.
class SurvivingTrianglesShape final : public btConcaveShape {
public:
    SurvivingTrianglesShape(const btConcaveShape& mesh, const PairTriangles& triangles)
        : m_mesh(mesh), m_triangles(triangles) {
        m_shapeType = mesh.getShapeType();
        setMargin(mesh.getMargin());
    }

    void processAllTriangles(btTriangleCallback* callback, const btVector3& /*aabbMin*/,
                             const btVector3& /*aabbMax*/) const override {
        btVector3 triangle[3];
        const std::vector<btVector3>& v = m_triangles.meshTriangleVertices;
        for (std::size_t i = 0; i < m_triangles.meshTriangles.size(); ++i) {
            triangle[0] = v[3 * i];
            triangle[1] = v[3 * i + 1];
            triangle[2] = v[3 * i + 2];
            callback->processTriangle(triangle, m_triangles.meshTriangles[i].part, m_triangles.meshTriangles[i].index);
        }
    }
    void getAabb(const btTransform& t, btVector3& aabbMin, btVector3& aabbMax) const override {
        m_mesh.getAabb(t, aabbMin, aabbMax);
    }
    void setLocalScaling(const btVector3& /*scaling*/) override {}
    const btVector3& getLocalScaling() const override { return m_mesh.getLocalScaling(); }
    void calculateLocalInertia(btScalar /*mass*/, btVector3& inertia) const override { inertia.setValue(0, 0, 0); }
    const char* getName() const override { return "CullideSurvivingTriangles"; }

private:
    const btConcaveShape& m_mesh;
    const PairTriangles& m_triangles;
};

/// A triangle mesh's wrapper with the mesh replaced by its surviving triangles (same object, transform and ids).
struct SurvivingMeshWrapper {
    SurvivingMeshWrapper(const btCollisionObjectWrapper* meshWrap, const PairTriangles& triangles)
        : shape(*static_cast<const btConcaveShape*>(meshWrap->getCollisionShape()), triangles),
          wrapper(meshWrap->m_parent, &shape, meshWrap->getCollisionObject(), meshWrap->getWorldTransform(),
                  meshWrap->m_partId, meshWrap->m_index) {}
    SurvivingTrianglesShape shape;
    btCollisionObjectWrapper wrapper;
};

/// GImpact pairs. By default each kind gets Bullet's contacts from Bullet's own algorithm reproduced or trimmed:
/// GImpact-GImpact (processAsBullet), GImpact-concave (processWithConcave), GImpact-convex (processWithConvex),
/// GImpact-plane (processWithPlane). Pairs
/// culled on request read CULLIDE's lists: GImpact-GImpact's surviving triangle pairs go straight to Bullet's
/// triangle-triangle routine (triangleContacts: collide_sat_triangles' loop), GImpact-triangle mesh runs Bullet's
/// gimpact_vs_concave on the mesh's surviving triangles only. Same size as btGImpactCollisionAlgorithm.
class CullideGImpactAlgorithm final : public btGImpactCollisionAlgorithm {
public:
    CullideGImpactAlgorithm(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* body0Wrap,
                            const btCollisionObjectWrapper* body1Wrap)
        : btGImpactCollisionAlgorithm(ci, body0Wrap, body1Wrap) {}

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override {
        if (!shortcutsSound(body0Wrap, body1Wrap, dispatchInfo, *resultOut)) {
            btGImpactCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        if (trimeshAgainstConvex(body0Wrap, body1Wrap) || trimeshAgainstConvex(body1Wrap, body0Wrap)) {
            processWithConvex(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        if (trimeshAgainstPlane(body0Wrap, body1Wrap) || trimeshAgainstPlane(body1Wrap, body0Wrap)) {
            processWithPlane(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        if (body0Wrap->getCollisionShape()->getShapeType() != GIMPACT_SHAPE_PROXYTYPE ||
            body1Wrap->getCollisionShape()->getShapeType() != GIMPACT_SHAPE_PROXYTYPE) {
            processWithMesh(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        if (!isGImpactMesh(*body0Wrap) || !isGImpactMesh(*body1Wrap)) {
            // A btGImpactCompoundShape, or a btGImpactMeshShapePart used on its own: Bullet's algorithm as it is.
            btGImpactCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        bool swapped = false;
        CullideDispatchStats* statsPtr = nullptr;
        const PairTriangles* triangles = cullideTrianglesFor(m_dispatcher, body0Wrap, body1Wrap, swapped, statsPtr);
        CullideDispatchStats& stats = *statsPtr;
        const auto* shape0 = static_cast<const btGImpactMeshShape*>(body0Wrap->getCollisionShape());
        const auto* shape1 = static_cast<const btGImpactMeshShape*>(body1Wrap->getCollisionShape());
        if (!allPartsHaveBoxSets(*shape0) || !allPartsHaveBoxSets(*shape1)) {
            // A part without a box set: Bullet then tests child boxes; let it.
            ++stats.fallbackPairs;
            btGImpactCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        if (triangles == nullptr) {  // not culled (the default for GImpact-GImpact): Bullet's contacts
            ++stats.fallbackPairs;
            processAsBullet(body0Wrap, body1Wrap, *shape0, *shape1, dispatchInfo, resultOut);
            return;
        }
        ++stats.cullidePairs;
        if (triangles->interpenetrating) {
            // The meshes intersect: GImpact's penetration contacts can come from triangle pairs far apart, which
            // CULLIDE's near pairs do not include. Bullet's contacts are kept (the fallback is optional).
            ++stats.penetrationPairs;
            processAsBullet(body0Wrap, body1Wrap, *shape0, *shape1, dispatchInfo, resultOut);
            return;
        }
        clearCache();  // GImpact recreates its manifold every frame; with no surviving pair it stays cleared
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
        if (triangles->pairs.empty()) {
            ++stats.clearedPairs;
            return;
        }

        // Pairs in (body0, body1) order, grouped by part pair, deterministic order.
        ordered.clear();
        for (const BulletTrianglePair& p : triangles->pairs) {
            const BulletTriangle& t0 = swapped ? p.b : p.a;
            const BulletTriangle& t1 = swapped ? p.a : p.b;
            ordered.push_back({t0.part, t1.part, t0.index, t1.index});
        }
        if (swapped) std::sort(ordered.begin(), ordered.end());

        detail::GImpactLeafIndex& leafIndex = detail::AdapterAccess::gimpactLeafIndex(cullideDispatcher(m_dispatcher));
        std::size_t begin = 0;
        while (begin < ordered.size()) {
            std::size_t end = begin;
            while (end < ordered.size() && ordered[end][0] == ordered[begin][0] &&
                   ordered[end][1] == ordered[begin][1])
                ++end;
            m_part0 = ordered[begin][0];
            m_part1 = ordered[begin][1];
            const btGImpactMeshShapePart* part0 = shape0->getMeshPart(m_part0);
            const btGImpactMeshShapePart* part1 = shape1->getMeshPart(m_part1);
            bulletCandidates(body0Wrap->getWorldTransform(), *part0, body1Wrap->getWorldTransform(), *part1,
                             leafIndex, ordered, begin, end);
            stats.trianglePairs += interleaved.size() / 2;
            if (!interleaved.empty()) {
                const detail::PartPair parts{part0, part1, m_part0, m_part1, &body0Wrap->getWorldTransform(),
                                             &body1Wrap->getWorldTransform()};
                detail::MeshContactScratch& scratch = detail::threadScratch();
                scratch.world0.begin(*part0, body0Wrap->getWorldTransform());
                scratch.world1.begin(*part1, body1Wrap->getWorldTransform());
                contacts.clear();
                part0->lockChildShapes();
                part1->lockChildShapes();
                detail::triangleContacts(parts, interleaved, scratch.world0, scratch.world1, contacts);
                part1->unlockChildShapes();
                part0->unlockChildShapes();
                addContacts(body0Wrap, body1Wrap, contacts);
            }
            begin = end;
        }
        if (getLastManifold() != nullptr)
            m_resultOut->refreshContactPoints();
        else
            ++stats.clearedPairs;
    }

    /// Bullet's GImpact-GImpact algorithm, contact for contact, at a fraction of its cost: per part pair in Bullet's
    /// order, Bullet's box-set pairs in Bullet's order (LeafPairSearch: Bullet's descent with each node box mapped
    /// into the other tree's frame once per call), through Bullet's own triangle routine (the conservative plane test,
    /// then the clip method), with each triangle mapped to world space and given its plane and edge planes once per
    /// call instead of once per pair it is in (detail::PreparedTriangle). Same inputs to the same routines in the same order: the same manifold. The points
    /// come from the dispatch's batch when it computed them ahead (on the narrow-phase threads) for these inputs.
    void processAsBullet(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                         const btGImpactMeshShape& shape0, const btGImpactMeshShape& shape1,
                         const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
        clearCache();
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
        const btTransform& trans0 = body0Wrap->getWorldTransform();
        const btTransform& trans1 = body1Wrap->getWorldTransform();
        const detail::ContactLists* ahead =
            detail::AdapterAccess::meshContacts(cullideDispatcher(m_dispatcher))
                .find(body0Wrap->getCollisionObject(), body1Wrap->getCollisionObject(), &shape0, &shape1, trans0,
                      trans1);
        if (ahead != nullptr) {
            ahead->forEach([&](const detail::MeshContact& c) { addContact(body0Wrap, body1Wrap, c); });
        } else {
            contacts.clear();
            detail::meshPairContacts(shape0, trans0, shape1, trans1, detail::threadScratch(), contacts);
            addContacts(body0Wrap, body1Wrap, contacts);
        }
        if (getLastManifold() != nullptr) m_resultOut->refreshContactPoints();
    }

    /// The points in order through Bullet's addContactPoint, each with its shape identifiers (as
    /// collide_sat_triangles adds them).
    void addContacts(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                     const std::vector<detail::MeshContact>& points) {
        for (const detail::MeshContact& c : points) addContact(body0Wrap, body1Wrap, c);
    }
    void addContact(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                    const detail::MeshContact& c) {
        m_part0 = c.part0;
        m_triface0 = c.face0;
        m_part1 = c.part1;
        m_triface1 = c.face1;
        addContactPoint(body0Wrap, body1Wrap, c.point, c.normal, c.distance);
    }

    /// Whether the adapter's paths give Bullet's points here: the world's own result (thresholdChecked), and, with
    /// SAT convex collision on (btDispatcherInfo::m_enableSatConvex), where Bullet's convex-triangle algorithm clips
    /// polyhedral faces, which the skip's reach test does not model, only GImpact against another GImpact mesh or a
    /// plane (whose points are computed as Bullet computes them).
    static bool shortcutsSound(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                               const btDispatcherInfo& dispatchInfo, const btManifoldResult& resultOut) {
        if (!thresholdChecked(resultOut)) return false;
        if (!dispatchInfo.m_enableSatConvex) return true;
        const bool meshPair = isGImpactMesh(*body0Wrap) && isGImpactMesh(*body1Wrap);
        return meshPair || trimeshAgainstPlane(body0Wrap, body1Wrap) || trimeshAgainstPlane(body1Wrap, body0Wrap);
    }

    /// A btGImpactMeshShape (not a GImpact compound, not a lone mesh part).
    static bool isGImpactMesh(const btCollisionObjectWrapper& w) {
        const btCollisionShape* shape = w.getCollisionShape();
        return shape->getShapeType() == GIMPACT_SHAPE_PROXYTYPE &&
               static_cast<const btGImpactShapeInterface*>(shape)->getGImpactShapeType() == CONST_GIMPACT_TRIMESH_SHAPE;
    }

    /// A GImpact triangle mesh (`mesh`) against a convex shape that is not a compound (`convex`).
    static bool trimeshAgainstConvex(const btCollisionObjectWrapper* mesh, const btCollisionObjectWrapper* convex) {
        const btCollisionShape* c = convex->getCollisionShape();
        return isGImpactMesh(*mesh) && c->isConvex() && !c->isCompound();
    }

    /// A GImpact triangle mesh (`mesh`) against a static plane (`plane`), where Bullet's algorithm collides the two by
    /// the mesh's vertices (GIMPACT_VS_PLANE_COLLISION).
    static bool trimeshAgainstPlane(const btCollisionObjectWrapper* mesh, const btCollisionObjectWrapper* plane) {
#ifdef GIMPACT_VS_PLANE_COLLISION
        return isGImpactMesh(*mesh) && plane->getCollisionShape()->getShapeType() == STATIC_PLANE_PROXYTYPE;
#else
        (void)mesh;
        (void)plane;
        return false;
#endif
    }

private:
    /// GImpact mesh against a convex shape (either order): Bullet's own per-triangle loop — its box query of each
    /// mesh part with the convex shape's box in the part's frame, then every candidate triangle against the convex
    /// shape through the dispatcher's convex algorithm, in Bullet's order and with Bullet's shape identifiers — minus
    /// the candidates that cannot make a contact point (convexCanTouch). Bullet's query box is the convex shape's
    /// AABB in the mesh's frame, which for a large or rotated convex shape (a ground box) holds most of the mesh, and
    /// every candidate costs a GJK run. The contacts are Bullet's: a skipped triangle is farther from the convex shape
    /// than btManifoldResult accepts a point.
    void processWithConvex(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                           const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
        bool recordSwapped = false;
        CullideDispatchStats* statsPtr = nullptr;
        const PairTriangles* verdict = cullideTrianglesFor(m_dispatcher, body0Wrap, body1Wrap, recordSwapped, statsPtr);
        CullideDispatchStats& stats = *statsPtr;
        clearCache();
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
        if (verdict != nullptr && verdict->pruned) {  // the culler proved the pair out of reach: no point this step
            ++stats.clearedPairs;
            return;
        }
        const bool swapped = !trimeshAgainstConvex(body0Wrap, body1Wrap);
        const btCollisionObjectWrapper* meshWrap = swapped ? body1Wrap : body0Wrap;
        const btCollisionObjectWrapper* convexWrap = swapped ? body0Wrap : body1Wrap;
        const auto* mesh = static_cast<const btGImpactMeshShape*>(meshWrap->getCollisionShape());
        ++stats.convexPairs;
        const detail::MeshContactBatch::ConvexAhead* ahead = convexAhead(body0Wrap, body1Wrap, dispatchInfo);
        // Computed on the workers for these inputs: the manifold made as Bullet's loop makes it (the dispatcher's
        // getNewManifold), then the points added in Bullet's order, if it has the threshold they were computed with.
        if (ahead != nullptr && ahead->manifold) checkManifold(body0Wrap, body1Wrap);
        if (ahead != nullptr &&
            (!ahead->manifold || getLastManifold()->getContactBreakingThreshold() == ahead->breakingThreshold)) {
            ahead->contacts.forEach([&](const detail::MeshContact& c) { addContact(body0Wrap, body1Wrap, c); });
            addCounts(ahead->counts, stats);
            ++stats.threadedConvexPairs;
        } else {  // Bullet's loop here (the manifold, if made above, is the one it would make first)
            int& part = swapped ? m_part1 : m_part0;
            for (part = mesh->getMeshPartCount(); part-- > 0;)
                partAgainstConvex(meshWrap, *mesh->getMeshPart(part), convexWrap, swapped, stats);
        }
        if (getLastManifold() != nullptr) m_resultOut->refreshContactPoints();
    }

    /// The pair's points computed ahead by the dispatch's batch (detail::convexChunkContacts), or nullptr.
    const detail::MeshContactBatch::ConvexAhead* convexAhead(const btCollisionObjectWrapper* body0Wrap,
                                                             const btCollisionObjectWrapper* body1Wrap,
                                                             const btDispatcherInfo& dispatchInfo) const {
        // The ahead loop's result has no closest-point threshold (a dispatch's has none; a query's may).
        if (m_resultOut->m_closestPointDistanceThreshold != 0) return nullptr;
        return detail::AdapterAccess::meshContacts(cullideDispatcher(m_dispatcher))
            .findConvex(body0Wrap->getCollisionObject(), body1Wrap->getCollisionObject(),
                        body0Wrap->getCollisionShape(), body1Wrap->getCollisionShape(),
                        body0Wrap->getWorldTransform(), body1Wrap->getWorldTransform(), dispatchInfo);
    }

    /// GImpact mesh against a concave shape (a triangle mesh, a heightfield; not a plane; either order), with Bullet's
    /// contacts: Bullet's gimpact_vs_concave per mesh part in Bullet's order — the concave shape's triangles within the
    /// part's box (processAllTriangles, Bullet's query and order), each as a triangle shape against the part
    /// through Bullet's per-triangle loop, with Bullet's shape identifiers and result wrappers — minus, for each mesh
    /// triangle, the part's candidate triangles that cannot make a point with it (partAgainstConvex). Bullet runs a
    /// convex-convex test (GJK) on every candidate of its box query.
    void processWithConcave(const btCollisionObjectWrapper* gimpactWrap, const btCollisionObjectWrapper* meshWrap,
                            bool swapped, const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut,
                            CullideDispatchStats& stats) {
        clearCache();
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
        ++stats.concavePairs;
        const auto* gimpact = static_cast<const btGImpactMeshShape*>(gimpactWrap->getCollisionShape());
        const auto* concave = static_cast<const btConcaveShape*>(meshWrap->getCollisionShape());
        // Bullet's gimpact_vs_concave computes the part's box in the concave shape's frame this way.
        const btTransform gimpactInConcave = meshWrap->getWorldTransform().inverse() * gimpactWrap->getWorldTransform();
        int& part = swapped ? m_part1 : m_part0;
        for (part = gimpact->getMeshPartCount(); part-- > 0;) {
            ConcaveTriangles callback(*this, gimpactWrap, meshWrap, *gimpact->getMeshPart(part), concave->getMargin(),
                                      swapped, stats);
            btVector3 lo, hi;
            gimpact->getMeshPart(part)->getAabb(gimpactInConcave, lo, hi);
            concave->processAllTriangles(&callback, lo, hi);
        }
        if (getLastManifold() != nullptr) m_resultOut->refreshContactPoints();
    }

    /// Bullet's btGImpactTriangleCallback: one triangle of the concave shape, as a triangle shape with the concave
    /// shape's margin and its part and index as the shape identifiers of its side, against one GImpact mesh part.
    class ConcaveTriangles final : public btTriangleCallback {
    public:
        ConcaveTriangles(CullideGImpactAlgorithm& algorithm, const btCollisionObjectWrapper* gimpactWrap,
                         const btCollisionObjectWrapper* meshWrap, const btGImpactMeshShapePart& part,
                         btScalar margin, bool swapped, CullideDispatchStats& stats)
            : m_algorithm(algorithm), m_gimpactWrap(gimpactWrap), m_meshWrap(meshWrap), m_part(part),
              m_margin(margin), m_swapped(swapped), m_stats(stats) {}

        void processTriangle(btVector3* triangle, int partId, int triangleIndex) override {
            btTriangleShapeEx shape(triangle[0], triangle[1], triangle[2]);
            shape.setMargin(m_margin);
            (m_swapped ? m_algorithm.m_part0 : m_algorithm.m_part1) = partId;
            (m_swapped ? m_algorithm.m_triface0 : m_algorithm.m_triface1) = triangleIndex;
            const btCollisionObjectWrapper wrap(m_meshWrap, &shape, m_meshWrap->getCollisionObject(),
                                                m_meshWrap->getWorldTransform(), partId, triangleIndex);
            const detail::WrapperInResult in(*m_algorithm.m_resultOut, wrap);
            m_algorithm.partAgainstConvex(m_gimpactWrap, m_part, &wrap, m_swapped, m_stats);
        }

    private:
        CullideGImpactAlgorithm& m_algorithm;
        const btCollisionObjectWrapper* m_gimpactWrap;
        const btCollisionObjectWrapper* m_meshWrap;
        const btGImpactMeshShapePart& m_part;
        btScalar m_margin;
        bool m_swapped;
        CullideDispatchStats& m_stats;
    };

    /// Bullet's gimpact_vs_shape for one GImpact mesh part against a convex shape: the part's box query with the
    /// convex shape's box in the part's frame, then the candidates through detail::collideCandidates (Bullet's loop
    /// minus the candidates out of reach) into the pair's result.
    void partAgainstConvex(const btCollisionObjectWrapper* meshWrap, const btGImpactMeshShapePart& meshPart,
                           const btCollisionObjectWrapper* convexWrap, bool swapped, CullideDispatchStats& stats) {
        const btCollisionShape* convex = convexWrap->getCollisionShape();
        candidates.resize(0);
        if (meshPart.hasBoxSet())
            detail::convexCandidates(meshWrap->getWorldTransform(), meshPart, *convex, convexWrap->getWorldTransform(),
                                     candidates);
        else
            gimpact_vs_shape_find_pairs(meshWrap->getWorldTransform(), convexWrap->getWorldTransform(), &meshPart,
                                        convex, candidates);
        if (candidates.size() == 0) return;
        // Bullet's loop makes the pair's manifold with its first candidate's algorithm (newAlgorithm's checkManifold,
        // bodies in the order the algorithm gets them), whether a point follows or not: so does this one, also when
        // every candidate is skipped, so that the dispatcher's manifolds (empty ones too, which the solver's island
        // sort sees) stay Bullet's.
        checkManifold(swapped ? convexWrap : meshWrap, swapped ? meshWrap : convexWrap);
        const detail::ConvexTarget target{m_dispatcher, getLastManifold(), m_resultOut, m_dispatchInfo};
        detail::ConvexCounts counts;
        meshPart.lockChildShapes();
        detail::collideCandidates({meshWrap, convexWrap, swapped}, meshPart, &candidates[0], candidates.size(),
                                  {m_part0, m_triface0, m_part1, m_triface1}, target, counts);
        meshPart.unlockChildShapes();
        addCounts(counts, stats);
    }

    static void addCounts(const detail::ConvexCounts& counts, CullideDispatchStats& stats) {
        stats.convexCandidates += counts.candidates;
        stats.convexTriangles += counts.triangles;
        stats.convexUnchecked += counts.unchecked;
    }

    /// GImpact against a shape that is neither GImpact nor convex (either order), but not a GImpact mesh against a
    /// plane (processWithPlane). A concave shape but a plane: processWithConcave (Bullet's contacts), or, for a pair
    /// culled with setGImpactMeshCulling, Bullet's processCollision with a stand-in mesh that enumerates
    /// the surviving triangles (mesh-local vertices as processAllTriangles yields them, same margin). Anything else
    /// (compounds, planes against GImpact compounds or lone parts): Bullet's.
    void processWithMesh(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                         const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
        bool swapped = false;
        CullideDispatchStats* statsPtr = nullptr;
        const PairTriangles* triangles = cullideTrianglesFor(m_dispatcher, body0Wrap, body1Wrap, swapped, statsPtr);
        CullideDispatchStats& stats = *statsPtr;
        const bool gimpactFirst = body0Wrap->getCollisionShape()->getShapeType() == GIMPACT_SHAPE_PROXYTYPE;
        const btCollisionObjectWrapper* gimpactWrap = gimpactFirst ? body0Wrap : body1Wrap;
        const btCollisionObjectWrapper* meshWrap = gimpactFirst ? body1Wrap : body0Wrap;
        if (!meshWrap->getCollisionShape()->isConcave() ||
            meshWrap->getCollisionShape()->getShapeType() == STATIC_PLANE_PROXYTYPE) {
            // A compound, a plane against a GImpact compound or lone part, ...: Bullet's algorithm as it is.
            ++stats.fallbackPairs;
            btGImpactCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        if (triangles == nullptr) {  // not culled (the default): Bullet's contacts
            if (isGImpactMesh(*gimpactWrap)) {
                processWithConcave(gimpactWrap, meshWrap, !gimpactFirst, dispatchInfo, resultOut, stats);
            } else {
                ++stats.fallbackPairs;
                btGImpactCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            }
            return;
        }
        ++stats.cullidePairs;
        clearCache();
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
        if (triangles->meshTriangles.empty()) {
            ++stats.clearedPairs;
            return;
        }
        stats.trianglePairs += triangles->meshTriangles.size();
        const SurvivingMeshWrapper surviving(meshWrap, *triangles);
        gimpact_vs_shape(gimpactWrap, &surviving.wrapper,
                         static_cast<const btGImpactShapeInterface*>(gimpactWrap->getCollisionShape()),
                         &surviving.shape, !gimpactFirst);
        if (getLastManifold() != nullptr) m_resultOut->refreshContactPoints();
    }

    /// GImpact mesh against a static plane (either order): Bullet's gimpact_vs_shape for a mesh and a plane — each
    /// part, last to first, through its vertex loop (gimpacttrimeshpart_vs_plane_collision) — with the vertices
    /// that cannot make a point ruled out first (GImpactPlaneContacts.h). Same points, same order. The culler keeps
    /// no record for these pairs: none is looked up.
    void processWithPlane(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
        clearCache();
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
        CullideDispatchStats& stats = detail::AdapterAccess::currentStats(cullideDispatcher(m_dispatcher));
        ++stats.planePairs;
        const bool swapped = !isGImpactMesh(*body0Wrap);  // the plane is the pair's first body
        const btCollisionObjectWrapper* gimpactWrap = swapped ? body1Wrap : body0Wrap;
        const btCollisionObjectWrapper* planeWrap = swapped ? body0Wrap : body1Wrap;
        const auto& mesh = *static_cast<const btGImpactMeshShape*>(gimpactWrap->getCollisionShape());
        const auto& plane = *static_cast<const btStaticPlaneShape*>(planeWrap->getCollisionShape());
        const btVector4 equation = detail::planeEquation(plane, planeWrap->getWorldTransform());
        // Bullet passes the plane's equation itself as the normal (its fourth component, the constant, is kept in the
        // manifold point's normal), or its negation (fourth component 0) for a plane that is the pair's first body.
        const btVector3 flipped = -static_cast<const btVector3&>(equation);
        const btVector3& normal = swapped ? flipped : static_cast<const btVector3&>(equation);
        const detail::PlanePointSink add = [&](const btVector3& vertex, btScalar distance) {
            addContactPoint(body0Wrap, body1Wrap, vertex, normal, distance);
        };
        detail::PlaneCounts counts;
        int& part = swapped ? m_part1 : m_part0;
        for (part = mesh.getMeshPartCount(); part--;)
            detail::planePartContacts(*mesh.getMeshPart(part), gimpactWrap->getWorldTransform(), equation,
                                      plane.getMargin(), add, counts);
        stats.planeVertices += counts.vertices;
        stats.planeVerticesTested += counts.tested;
        if (getLastManifold() != nullptr) m_resultOut->refreshContactPoints();
    }

    static thread_local std::vector<std::array<int, 4>> ordered;  // part0, part1, tri0, tri1
    static thread_local std::vector<detail::MeshContact> contacts;
    static thread_local btAlignedObjectArray<int> candidates;      // Bullet's box query of one mesh part
    static thread_local std::vector<int> interleaved;

    /// Keeps, of ordered[begin, end) (one part pair), the triangle pairs that Bullet's own candidate search
    /// (btGImpactQuantizedBvh::find_collision) would also produce, into `interleaved`: the parts' quantized leaf
    /// boxes overlap in part 0's frame, tested as Bullet tests them (the 15-axis test for the roots, the 6 face axes
    /// below). CULLIDE's pairs are near pairs; Bullet's are box-overlapping pairs; the clip method runs on pairs in
    /// both. Both parts have box sets.
    static void bulletCandidates(const btTransform& trans0, const btGImpactMeshShapePart& part0,
                                 const btTransform& trans1, const btGImpactMeshShapePart& part1,
                                 detail::GImpactLeafIndex& leafIndex, const std::vector<std::array<int, 4>>& pairs,
                                 std::size_t begin, std::size_t end) {
        interleaved.clear();
        const btGImpactBoxSet& set0 = *part0.getBoxSet();
        const btGImpactBoxSet& set1 = *part1.getBoxSet();
        BT_BOX_BOX_TRANSFORM_CACHE cache;
        cache.calc_from_homogenic(trans0, trans1);
        btAABB box0, box1;
        set0.getNodeBound(0, box0);
        set1.getNodeBound(0, box1);
        if (!box0.overlapping_trans_cache(box1, cache, true)) return;  // Bullet finds no pair at all
        const bool rootsOnly = set0.isLeafNode(0) && set1.isLeafNode(0);
        std::vector<int>& leaves0 = leafIndex.leavesOf(set0);
        std::vector<int>& leaves1 = &set1 == &set0 ? leaves0 : leafIndex.leavesOf(set1);
        for (std::size_t i = begin; i < end; ++i) {
            const int leaf0 = detail::GImpactLeafIndex::leafOf(set0, leaves0, pairs[i][2]);
            const int leaf1 = detail::GImpactLeafIndex::leafOf(set1, leaves1, pairs[i][3]);
            if (leaf0 < 0 || leaf1 < 0) continue;  // not in Bullet's box set: Bullet never tests it either
            if (!rootsOnly) {
                set0.getNodeBound(leaf0, box0);
                set1.getNodeBound(leaf1, box1);
                if (!box0.overlapping_trans_cache(box1, cache, false)) continue;
            }
            interleaved.push_back(pairs[i][2]);
            interleaved.push_back(pairs[i][3]);
        }
    }

    static bool allPartsHaveBoxSets(const btGImpactMeshShape& shape) {
        for (int part = 0; part < shape.getMeshPartCount(); ++part)
            if (!shape.getMeshPart(part)->hasBoxSet()) return false;
        return true;
    }

public:
    struct CreateFunc : btCollisionAlgorithmCreateFunc {
        btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                       const btCollisionObjectWrapper* body0Wrap,
                                                       const btCollisionObjectWrapper* body1Wrap) override {
            void* mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(CullideGImpactAlgorithm));
            return new (mem) CullideGImpactAlgorithm(ci, body0Wrap, body1Wrap);
        }
    };
};

thread_local std::vector<std::array<int, 4>> CullideGImpactAlgorithm::ordered;
thread_local std::vector<int> CullideGImpactAlgorithm::interleaved;
thread_local btAlignedObjectArray<int> CullideGImpactAlgorithm::candidates;
thread_local std::vector<detail::MeshContact> CullideGImpactAlgorithm::contacts;

/// Convex hull vs triangle mesh: Bullet's btConvexConcaveCollisionAlgorithm (btConvexTriangleCallback, persistent
/// manifold) driven with the surviving mesh triangles only. Same size as the base class.
template <bool MeshFirst>
class CullideConvexMeshAlgorithm final : public btConvexConcaveCollisionAlgorithm {
public:
    CullideConvexMeshAlgorithm(const btCollisionAlgorithmConstructionInfo& ci,
                               const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap)
        : btConvexConcaveCollisionAlgorithm(ci, body0Wrap, body1Wrap, MeshFirst) {}

    void processCollision(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                          const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) override {
        bool swapped = false;
        CullideDispatchStats* statsPtr = nullptr;
        const PairTriangles* triangles = cullideTrianglesFor(m_dispatcher, body0Wrap, body1Wrap, swapped, statsPtr);
        CullideDispatchStats& stats = *statsPtr;
        const btCollisionObjectWrapper* meshWrap = MeshFirst ? body0Wrap : body1Wrap;
        if (triangles == nullptr || !meshWrap->getCollisionShape()->isConcave() || !thresholdChecked(*resultOut)) {
            ++stats.fallbackPairs;
            btConvexConcaveCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
            return;
        }
        ++stats.cullidePairs;
        if (triangles->meshTriangles.empty()) {
            ++stats.clearedPairs;
            btManifoldArray manifolds;
            getAllContactManifolds(manifolds);
            for (int i = 0; i < manifolds.size(); ++i) m_dispatcher->clearManifold(manifolds[i]);
            return;
        }
        stats.trianglePairs += triangles->meshTriangles.size();
        const SurvivingMeshWrapper surviving(meshWrap, *triangles);
        const btCollisionObjectWrapper* mesh = &surviving.wrapper;
        btConvexConcaveCollisionAlgorithm::processCollision(MeshFirst ? mesh : body0Wrap, MeshFirst ? body1Wrap : mesh,
                                                            dispatchInfo, resultOut);
    }

    struct CreateFunc : btCollisionAlgorithmCreateFunc {
        btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                       const btCollisionObjectWrapper* body0Wrap,
                                                       const btCollisionObjectWrapper* body1Wrap) override {
            void* mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(CullideConvexMeshAlgorithm));
            return new (mem) CullideConvexMeshAlgorithm(ci, body0Wrap, body1Wrap);
        }
    };
};

CullideGImpactAlgorithm::CreateFunc g_gimpactCreate;
CullideConvexMeshAlgorithm<false>::CreateFunc g_convexMeshCreate;
CullideConvexMeshAlgorithm<true>::CreateFunc g_meshConvexCreate;

/// A convex shape the broadphase culls as triangles: a convex hull body, or a convex child of a compound (the
/// compound algorithm wraps its children; the compound is culled as its children's hulls and boxes).
bool culledConvex(const btCollisionObjectWrapper* w) {
    const btCollisionShape* shape = w->getCollisionShape();
    if (shape->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE) return true;
    const btCollisionObject* object = w->getCollisionObject();
    return shape->isConvex() && object != nullptr && object->getCollisionShape() != shape &&
           object->getCollisionShape()->getShapeType() == COMPOUND_SHAPE_PROXYTYPE;
}

/// The shape as a btGImpactMeshShape whose parts all have box sets (what the mesh-mesh path reads), or nullptr.
const btGImpactMeshShape* asGImpactMesh(const btCollisionShape* shape) {
    if (shape->getShapeType() != GIMPACT_SHAPE_PROXYTYPE ||
        static_cast<const btGImpactShapeInterface*>(shape)->getGImpactShapeType() != CONST_GIMPACT_TRIMESH_SHAPE)
        return nullptr;
    const auto* mesh = static_cast<const btGImpactMeshShape*>(shape);
    for (int part = 0; part < mesh->getMeshPartCount(); ++part)
        if (!mesh->getMeshPart(part)->hasBoxSet()) return nullptr;
    return mesh;
}

/// Bullet's dispatch loop (btCollisionDispatcher's: the near callback for every pair, in the pair cache's order),
/// except for pairs provably apart (ApartPairs.h): their points are cleared and their algorithm is not called. Given
/// a test for pairs that may run on the narrow-phase threads (ThreadedPairs.h) and a stream, it hands those pairs to
/// the stream (the worker pool collides them meanwhile) and runs the others itself, in the cache's order, so that
/// manifolds and algorithms are made and freed in Bullet's order. Without a stream it runs every pair itself.
class DispatchLoop final : public btOverlapCallback {
public:
    /// The kind of a pair's algorithm if it may run on a narrow-phase thread, else AlgorithmKind::Other.
    using Threadable = std::function<bullet::AlgorithmKind(btBroadphasePair&)>;
    DispatchLoop(btCollisionDispatcher& dispatcher, const btDispatcherInfo& info, const Threadable* threadable,
                 bullet::PairStream* stream)
        : m_dispatcher(dispatcher), m_info(info), m_threadable(threadable), m_stream(stream) {}
    bool processOverlap(btBroadphasePair& pair) override {
        if (bullet::skipIfApart(pair, m_dispatcher, m_scratch)) {
            ++skipped;
            return false;
        }
        const bullet::AlgorithmKind kind = m_threadable != nullptr ? (*m_threadable)(pair) : bullet::AlgorithmKind::Other;
        if (!bullet::worthHandingOff(kind)) {
            btCollisionDispatcher::defaultNearCallback(pair, m_dispatcher, m_info);
        } else {
            threadableCost += bullet::typicalCost(kind);
            if (m_stream == nullptr || !m_stream->push(&pair)) bullet::collidePair(pair, m_info);
        }
        return false;  // the pair stays in the cache
    }
    std::size_t skipped = 0;
    std::size_t threadableCost = 0;  ///< bullet::typicalCost of the pairs that could run on the threads

private:
    btCollisionDispatcher& m_dispatcher;
    const btDispatcherInfo& m_info;
    const Threadable* m_threadable;
    bullet::PairStream* m_stream;
    btManifoldArray m_scratch;
};

/// Marks the worker pool as serving the dispatch under way, until the scope ends (also on an exception).
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
    bullet::PairStream& stream;
    ~CloseWhenDone() { stream.close(); }
};

template <typename T>
bool registeredIs(const btCollisionAlgorithmCreateFunc* f) {
    return f != nullptr && typeid(*f) == typeid(T);
}


}  // namespace

CullideCollisionDispatcher::CullideCollisionDispatcher(detail::PrecisionChecked,
                                                       btCollisionConfiguration* collisionConfiguration,
                                                       CullideBroadphase* broadphase)
    : btCollisionDispatcher(collisionConfiguration),
      m_broadphase(broadphase),
      m_leafIndex(std::make_unique<detail::GImpactLeafIndex>()),
      m_meshContacts(std::make_unique<detail::MeshContactBatch>()) {}

void CullideCollisionDispatcher::setNarrowPhaseThreads(unsigned threads) {
    if (threads > kMaxNarrowPhaseThreads)
        throw std::invalid_argument("CullideCollisionDispatcher::setNarrowPhaseThreads: " + std::to_string(threads) +
                                    " threads requested, at most " + std::to_string(kMaxNarrowPhaseThreads));
    if (threads == m_threads) return;
    m_threads = threads;
    m_pool.reset();
}

namespace {

/// The default narrow-phase thread count: the machine's hardware threads, at most 8. Read once per process:
/// std::thread::hardware_concurrency reads /sys/devices/system/cpu/online (three system calls, ~8 us), which every
/// dispatch paid before (the whole narrow phase of a 55-box stack is ~25 us).
unsigned machineThreads() {
    static const unsigned threads = std::min(8u, std::max(1u, std::thread::hardware_concurrency()));
    return threads;
}

}  // namespace

namespace {

/// GImpact-convex pairs are computed ahead when the previous step ran at least this many of their triangles (~40 us
/// of GJK on the 2-core machine, about what waking the workers costs) or the batch runs anyway for mesh-mesh pairs.
constexpr std::size_t kMinAheadConvexTriangles = 64;

/// Whether a GImpact-convex pair of the cache (objects in its order; one shape a btGImpactMeshShape whose parts all
/// have box sets) may be computed ahead: the convex shape's algorithm with a triangle may run on a worker, the pair's
/// algorithm is the dispatcher's GImpact one, and the culler has not proved it out of reach.
bool convexPairAhead(const btCollisionObject& object0, const btCollisionObject& object1,
                     const bullet::CreateFuncTable& funcs, const CullideBroadphase* broadphase) {
    const btCollisionShape& shape0 = *object0.getCollisionShape();
    const btCollisionShape& shape1 = *object1.getCollisionShape();
    const bool convexFirst = shape0.getShapeType() != GIMPACT_SHAPE_PROXYTYPE;
    const btCollisionShape& convex = convexFirst ? shape0 : shape1;
    if (!convex.isConvex() || convex.isCompound() || !bullet::objectsMayThread(object0, object1)) return false;
    // The pair's algorithm is this dispatcher's GImpact one (the application registered Bullet's).
    if (!registeredIs<btGImpactCollisionAlgorithm::CreateFunc>(
            funcs[shape0.getShapeType()][shape1.getShapeType()]))
        return false;
    const int triangle = TRIANGLE_SHAPE_PROXYTYPE, convexType = convex.getShapeType();
    const btCollisionAlgorithmCreateFunc* triangleFunc =
        convexFirst ? funcs[convexType][triangle] : funcs[triangle][convexType];
    if (!bullet::convexTriangleThreadable(convex, triangleFunc) || !detail::pointsIndependentOfManifold(triangleFunc))
        return false;
    if (broadphase == nullptr || !broadphase->getGImpactConvexCulling()) return true;
    // A pair the culler proved out of reach gets no point this step: nothing to compute.
    const btCollisionObjectWrapper w0(nullptr, &shape0, &object0, object0.getWorldTransform(), -1, -1);
    const btCollisionObjectWrapper w1(nullptr, &shape1, &object1, object1.getWorldTransform(), -1, -1);
    bool swapped = false;
    const PairTriangles* record = detail::AdapterAccess::trianglePairsFor(*broadphase, &w0, &w1, swapped);
    return record == nullptr || !record->pruned;
}

}  // namespace

bool CullideCollisionDispatcher::listMeshPairs(btOverlappingPairCache* pairCache,
                                               const btDispatcherInfo& dispatchInfo) {
    detail::MeshContactBatch& batch = *m_meshContacts;
    batch.clear();
    const unsigned threads = narrowPhaseThreads();
    // Only where the dispatch will run the GImpact algorithm's mesh-mesh path: discrete dispatch, Bullet's GImpact
    // algorithm registered (then replaced by ours in findAlgorithm), more than one thread to use.
    if (threads < 2 || dispatchInfo.m_dispatchFunc != btDispatcherInfo::DISPATCH_DISCRETE ||
        !registeredIs<btGImpactCollisionAlgorithm::CreateFunc>(
            m_doubleDispatchContactPoints[GIMPACT_SHAPE_PROXYTYPE][GIMPACT_SHAPE_PROXYTYPE]))
        return false;
    // GImpact-convex pairs: their triangles' algorithms run on the workers, so only with no hook that would see a
    // worker's points, and when the previous step collided enough of their triangles.
    const bool convexAhead = m_lastStep.convexTriangles >= kMinAheadConvexTriangles &&
                             bullet::dispatchMayThread(dispatchInfo) && !dispatchInfo.m_enableSatConvex;
    const int count = pairCache->getNumOverlappingPairs();
    const btBroadphasePair* pairs = count > 0 ? pairCache->getOverlappingPairArrayPtr() : nullptr;
    for (int i = 0; i < count; ++i) {
        const auto* object0 = static_cast<const btCollisionObject*>(pairs[i].m_pProxy0->m_clientObject);
        const auto* object1 = static_cast<const btCollisionObject*>(pairs[i].m_pProxy1->m_clientObject);
        const btGImpactMeshShape* shape0 = asGImpactMesh(object0->getCollisionShape());
        const btGImpactMeshShape* shape1 = asGImpactMesh(object1->getCollisionShape());
        if ((shape0 == nullptr && shape1 == nullptr) || !needsCollision(object0, object1)) continue;
        if (shape0 == nullptr || shape1 == nullptr) {
            if (convexAhead && convexPairAhead(*object0, *object1, m_doubleDispatchContactPoints, m_broadphase))
                batch.addConvex(object0, object1, *object0->getCollisionShape(), *object1->getCollisionShape(),
                                object0->getWorldTransform(), object1->getWorldTransform(), *this, dispatchInfo);
            continue;
        }
        if (m_broadphase != nullptr && m_broadphase->getGImpactPairCulling()) {
            // A culled pair reads the culler's triangle pairs instead, unless its meshes interpenetrate.
            const btCollisionObjectWrapper w0(nullptr, shape0, object0, object0->getWorldTransform(), -1, -1);
            const btCollisionObjectWrapper w1(nullptr, shape1, object1, object1->getWorldTransform(), -1, -1);
            bool swapped = false;
            const PairTriangles* record = detail::AdapterAccess::trianglePairsFor(*m_broadphase, &w0, &w1, swapped);
            if (record != nullptr && !record->interpenetrating) continue;
        }
        batch.add(object0, object1, *shape0, *shape1, object0->getWorldTransform(), object1->getWorldTransform());
    }
    return batch.size() > 0;
}


CullideCollisionDispatcher::~CullideCollisionDispatcher() = default;

unsigned CullideCollisionDispatcher::narrowPhaseThreads() const {
    return m_threads != 0 ? m_threads : machineThreads();
}

TaskPool& CullideCollisionDispatcher::pool(unsigned threads) {
    if (!m_pool || m_pool->size() != threads) m_pool = std::make_unique<TaskPool>(threads);
    return *m_pool;
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

namespace {

/// The dispatcher's algorithm for a pair in place of `registered` (the application's table entry), or nullptr for
/// the table's own.
btCollisionAlgorithmCreateFunc* replacementFor(const btCollisionObjectWrapper* body0Wrap,
                                               const btCollisionObjectWrapper* body1Wrap,
                                               const btCollisionAlgorithmCreateFunc* registered,
                                               const CullideBroadphase& broadphase) {
    const int t0 = body0Wrap->getCollisionShape()->getShapeType();
    const int t1 = body1Wrap->getCollisionShape()->getShapeType();
    const bool gimpact = t0 == GIMPACT_SHAPE_PROXYTYPE || t1 == GIMPACT_SHAPE_PROXYTYPE;
    const bool convexMesh = bullet::isTriangleMeshType(t0) || bullet::isTriangleMeshType(t1);
    // Most lookups come from a per-triangle loop (a GImpact triangle or a mesh triangle against a convex shape):
    // neither kind, and answered here.
    if (!gimpact && !convexMesh) return nullptr;
    // Bullet's algorithm is replaced only where the application's table holds Bullet's own one, so
    // btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher) (or not calling it) keeps its meaning and any
    // custom registration wins.
    // GImpact against GImpact or against a concave shape (triangle meshes, heightfields, ...) but a plane, which
    // Bullet's algorithm collides with the mesh's vertices (GIMPACT_VS_PLANE_COLLISION).
    const auto concave = [](int t) { return btBroadphaseProxy::isConcave(t) && t != STATIC_PLANE_PROXYTYPE; };
    const bool gimpactPair = (t0 == GIMPACT_SHAPE_PROXYTYPE && concave(t1)) ||
                             (concave(t0) && t1 == GIMPACT_SHAPE_PROXYTYPE);
    const bool gimpactConvexPair = CullideGImpactAlgorithm::trimeshAgainstConvex(body0Wrap, body1Wrap) ||
                                   CullideGImpactAlgorithm::trimeshAgainstConvex(body1Wrap, body0Wrap);
    // A GImpact mesh against a plane: Bullet's vertex loop, most vertices ruled out by a cheaper bound first.
    const bool gimpactPlanePair = CullideGImpactAlgorithm::trimeshAgainstPlane(body0Wrap, body1Wrap) ||
                                  CullideGImpactAlgorithm::trimeshAgainstPlane(body1Wrap, body0Wrap);
    if ((gimpactPair || gimpactConvexPair || gimpactPlanePair) &&
        registeredIs<btGImpactCollisionAlgorithm::CreateFunc>(registered))
        return &g_gimpactCreate;
    // Convex-mesh pairs read the culler's triangles only with convex-mesh culling on; otherwise Bullet's own
    // algorithm runs them without a record lookup per pair and step.
    if (!convexMesh || !broadphase.getConvexMeshCulling()) return nullptr;
    if (bullet::isTriangleMeshType(t1) && culledConvex(body0Wrap) &&
        registeredIs<btConvexConcaveCollisionAlgorithm::CreateFunc>(registered))
        return &g_convexMeshCreate;
    if (bullet::isTriangleMeshType(t0) && culledConvex(body1Wrap) &&
        registeredIs<btConvexConcaveCollisionAlgorithm::SwappedCreateFunc>(registered))
        return &g_meshConvexCreate;
    return nullptr;
}

}  // namespace

btCollisionAlgorithm* CullideCollisionDispatcher::findAlgorithm(const btCollisionObjectWrapper* body0Wrap,
                                                                const btCollisionObjectWrapper* body1Wrap,
                                                                btPersistentManifold* sharedManifold,
                                                                ebtDispatcherQueryType queryType) {
    if (queryType == BT_CONTACT_POINT_ALGORITHMS && m_broadphase != nullptr) {
        const btCollisionAlgorithmCreateFunc* registered =
            m_doubleDispatchContactPoints[body0Wrap->getCollisionShape()->getShapeType()]
                                         [body1Wrap->getCollisionShape()->getShapeType()];
        if (btCollisionAlgorithmCreateFunc* replacement =
                replacementFor(body0Wrap, body1Wrap, registered, *m_broadphase)) {
            btCollisionAlgorithmConstructionInfo ci;
            ci.m_dispatcher1 = this;
            ci.m_manifold = sharedManifold;
            return replacement->CreateCollisionAlgorithm(ci, body0Wrap, body1Wrap);
        }
    }
    return btCollisionDispatcher::findAlgorithm(body0Wrap, body1Wrap, sharedManifold, queryType);
}

void CullideCollisionDispatcher::dispatchOwnPairs(btOverlappingPairCache* pairCache, const btDispatcherInfo& dispatchInfo,
                                                  btDispatcher* dispatcher, bool mayStream) {
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
        const PoolClaim claim{m_poolBusy};  // a dispatch nested in a pair's algorithm (rare) runs without the pool
        bullet::PairStream stream;
        stream.reset(static_cast<std::size_t>(pairCache->getNumOverlappingPairs()));
        DispatchLoop loop(*this, dispatchInfo, &threadable, &stream);
        const auto produce = [&] {
            const CloseWhenDone closer{stream};
            pairCache->processAllOverlappingPairs(&loop, dispatcher, dispatchInfo);
        };
        const auto consume = [&](std::size_t, std::size_t) { stream.consume(dispatchInfo); };
        pool(threads).parallelFor(threads, 1, consume, produce);
        m_current.apartPairs = loop.skipped;
        m_current.threadedPairs = stream.size();
        m_lastThreadableCost = loop.threadableCost;
    } else {
        DispatchLoop loop(*this, dispatchInfo, mayThread ? &threadable : nullptr, nullptr);
        pairCache->processAllOverlappingPairs(&loop, dispatcher, dispatchInfo);
        m_current.apartPairs = loop.skipped;
        if (mayThread) m_lastThreadableCost = loop.threadableCost;
    }
}

void CullideCollisionDispatcher::dispatchAllCollisionPairs(btOverlappingPairCache* pairCache,
                                                           const btDispatcherInfo& dispatchInfo,
                                                           btDispatcher* dispatcher) {
    const CullideDispatchStats outer = m_current;  // nested dispatches (rare) keep the outer counters
    m_current.reset();
    const bool ownCache = m_broadphase != nullptr && pairCache == m_broadphase->getOverlappingPairCache();
    if (ownCache) m_leafIndex->beginDispatch();  // once per step, not for a character controller's private cache
    cullide::Timer watch;
    const auto dispatchPairs = [&](bool mayStream) {
        if (ownCache && dispatchInfo.m_dispatchFunc == btDispatcherInfo::DISPATCH_DISCRETE &&
            getNearCallback() == &btCollisionDispatcher::defaultNearCallback)
            dispatchOwnPairs(pairCache, dispatchInfo, dispatcher, mayStream);
        else
            btCollisionDispatcher::dispatchAllCollisionPairs(pairCache, dispatchInfo, dispatcher);
    };
    // GImpact mesh-mesh pairs: the workers compute their contacts while this thread dispatches.
    detail::MeshContactBatch& batch = *m_meshContacts;
    if (!m_poolBusy && listMeshPairs(pairCache, dispatchInfo)) {
        const PoolClaim claim{m_poolBusy};  // a dispatch nested in a pair's algorithm leaves the batch and pool alone
        batch.run(&pool(narrowPhaseThreads()), [&] { dispatchPairs(false); });
        m_current.threadedMeshPairs = batch.size() - batch.convexCount();
        m_current.threadedTasks = batch.taskCount();
        batch.clear();
    } else {
        dispatchPairs(true);
    }
    m_current.dispatchMs = watch.ms();
    m_current.pairsDispatched = static_cast<std::size_t>(pairCache->getNumOverlappingPairs());
    m_total.pairsDispatched += m_current.pairsDispatched;
    m_total.cullidePairs += m_current.cullidePairs;
    m_total.trianglePairs += m_current.trianglePairs;
    m_total.fallbackPairs += m_current.fallbackPairs;
    m_total.clearedPairs += m_current.clearedPairs;
    m_total.penetrationPairs += m_current.penetrationPairs;
    m_total.convexPairs += m_current.convexPairs;
    m_total.concavePairs += m_current.concavePairs;
    m_total.convexCandidates += m_current.convexCandidates;
    m_total.convexTriangles += m_current.convexTriangles;
    m_total.convexUnchecked += m_current.convexUnchecked;
    m_total.threadedMeshPairs += m_current.threadedMeshPairs;
    m_total.threadedConvexPairs += m_current.threadedConvexPairs;
    m_total.threadedTasks += m_current.threadedTasks;
    m_total.apartPairs += m_current.apartPairs;
    m_total.threadedPairs += m_current.threadedPairs;
    m_total.planePairs += m_current.planePairs;
    m_total.planeVertices += m_current.planeVertices;
    m_total.planeVerticesTested += m_current.planeVerticesTested;
    m_total.dispatchMs += m_current.dispatchMs;
    if (ownCache) m_lastStep = m_current;
    m_current = outer;
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
