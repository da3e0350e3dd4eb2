#include "broadphase/PairRecords.h"

#include "broadphase/BulletProxies.h"
#include "cullide/TriangleTest.h"

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>

#include <algorithm>
#include <iterator>

namespace cullide::bullet {
namespace {

/// The mesh's surviving triangles of a convex/GImpact-vs-triangle-mesh pair, sorted as Bullet names them, with their
/// mesh-local vertices.
void survivingMeshTriangles(const ShapeTriangles& mesh, bool meshIsA, const ObjectPair& op, PairTriangles& out) {
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

bool bulletOrder(const BulletTrianglePair& x, const BulletTrianglePair& y) {
    if (x.a.part != y.a.part) return x.a.part < y.a.part;
    if (x.b.part != y.b.part) return x.b.part < y.b.part;
    if (x.a.index != y.a.index) return x.a.index < y.a.index;
    return x.b.index < y.b.index;
}

}  // namespace

void PairRecords::TriangleBoxes::begin(std::size_t triangles) {
    if (boxes.size() < triangles) {
        boxes.resize(triangles);
        stamp.resize(triangles, 0);
    }
    if (++current == 0) {  // wrapped: forget every stamp
        std::fill(stamp.begin(), stamp.end(), 0);
        current = 1;
    }
}

const Aabb& PairRecords::TriangleBoxes::of(const TriangleMesh& m, std::uint32_t t) {
    if (stamp[t] != current) {
        Aabb b;
        for (std::uint32_t v : m.triangles[t]) b.grow(m.vertices[v]);
        boxes[t] = b;
        stamp[t] = current;
    }
    return boxes[t];
}

void PairRecords::beginStep(std::uint64_t step, bool deepPenetrationFallback) {
    m_step = step;
    m_records.clear();
    if (!deepPenetrationFallback) m_penetratingUntil.clear();
    for (auto it = m_penetratingUntil.begin(); it != m_penetratingUntil.end();)
        it = it->second < step ? m_penetratingUntil.erase(it) : std::next(it);
}

bool PairRecords::recentlyPenetrating(const btBroadphaseProxy* a, const btBroadphaseProxy* b) const {
    if (m_penetratingUntil.empty()) return false;
    const auto it = m_penetratingUntil.find(pairKey(a, b));
    return it != m_penetratingUntil.end() && m_step <= it->second;
}

void PairRecords::recordPenetrating(const btBroadphaseProxy* a, const btBroadphaseProxy* b) {
    Record rec = recordFor(a, b);
    rec.triangles.interpenetrating = true;
    m_records[pairKey(a, b)] = std::move(rec);
}

/// Record orientation (first = lower unique id) of the culler's pair (pa, pb), shapes and transforms as now.
PairRecords::Record PairRecords::recordFor(const btBroadphaseProxy* pa, const btBroadphaseProxy* pb) {
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

void PairRecords::recordVerdicts(const Result& result, CullFrame& frame, bool deepPenetrationFallback,
                                 CullideFrameStats& stats) {
    const std::vector<ObjectIndexPair>& candidates = frame.pairs();
    std::vector<std::uint8_t> kept(candidates.size(), 0);
    for (const ObjectPair& op : result.pairs) {
        const ObjectIndexPair key(std::min(op.a, op.b), std::max(op.a, op.b));
        const auto it = std::lower_bound(candidates.begin(), candidates.end(), key);
        if (it != candidates.end() && *it == key) kept[std::size_t(it - candidates.begin())] = 1;
        ++stats.cullerPairs;
        recordKept(op, frame, deepPenetrationFallback, stats);
    }
    for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (kept[i]) continue;
        Record rec = recordFor(frame.proxyOf(candidates[i].first), frame.proxyOf(candidates[i].second));
        rec.triangles.pruned = true;
        m_records[pairKey(rec.first, rec.second)] = std::move(rec);
        ++stats.prunedPairs;
    }
}

/// The record of a pair the culler kept with surviving triangles (GImpact-GImpact, or a convex or GImpact shape
/// against a triangle mesh); other kept pairs get none (the dispatcher runs Bullet's algorithm for them).
void PairRecords::recordKept(const ObjectPair& op, CullFrame& frame, bool deepPenetrationFallback,
                             CullideFrameStats& stats) {
    btBroadphaseProxy* pa = frame.proxyOf(op.a);
    btBroadphaseProxy* pb = frame.proxyOf(op.b);
    CulledObject& ca = frame.culled(pa);
    CulledObject& cb = frame.culled(pb);
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
        rec.triangles.interpenetrating =
            nearGImpactPairs(ca, cb, op, flip, deepPenetrationFallback, rec.triangles.pairs);
        stats.trianglePairs += rec.triangles.pairs.size();
        if (rec.triangles.interpenetrating) {
            ++stats.interpenetratingPairs;
            m_penetratingUntil[pairKey(pa, pb)] = m_step + kPenetrationRecheck;
        }
    } else {
        const bool meshIsA = ka == GeometryKind::TriangleMesh;
        survivingMeshTriangles(meshIsA ? *ca.geometry : *cb.geometry, meshIsA, op, rec.triangles);
        stats.trianglePairs += rec.triangles.meshTriangles.size();
    }
    m_records[pairKey(pa, pb)] = std::move(rec);
}

/// GImpact-GImpact: the culler's triangle pairs (every pair within the culling margin, which covers the reach of
/// Bullet's box-set search: CullingPolicy.h), as Bullet's (part, index) pairs in record orientation, sorted. The
/// dispatcher keeps of them those that Bullet's own search would also produce (its leaf-box test, exactly), so no
/// pair is dropped here on a narrower test. Returns whether the meshes intersect (some kept pair shares a point;
/// tested only with the fallback on), and then no list: the dispatcher runs Bullet's full algorithm.
bool PairRecords::nearGImpactPairs(const CulledObject& ca, const CulledObject& cb, const ObjectPair& op, bool flip,
                                   bool deepPenetrationFallback, std::vector<BulletTrianglePair>& out) {
    const TriangleMesh& wa = ca.world;
    const TriangleMesh& wb = cb.world;
    m_boxesA.begin(wa.triangles.size());
    m_boxesB.begin(wb.triangles.size());
    out.reserve(op.triangles.size());
    for (const TrianglePair& tp : op.triangles) {
        if (deepPenetrationFallback && m_boxesA.of(wa, tp.a).overlaps(m_boxesB.of(wb, tp.b))) {
            // Triangles that meet have meeting boxes.
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
    if (!std::is_sorted(out.begin(), out.end(), bulletOrder)) std::sort(out.begin(), out.end(), bulletOrder);
    return false;
}

const PairTriangles* PairRecords::find(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                                       bool& swapped) const {
    swapped = false;
    if (m_records.empty() || w0 == nullptr || w1 == nullptr) return nullptr;
    const btCollisionObject* o0 = w0->getCollisionObject();
    const btCollisionObject* o1 = w1->getCollisionObject();
    if (o0 == nullptr || o1 == nullptr) return nullptr;
    // A child wrapper (compound algorithm, GImpact part) is trusted only on a compound's side of the record.
    const bool child0 = w0->getCollisionShape() != o0->getCollisionShape();
    const bool child1 = w1->getCollisionShape() != o1->getCollisionShape();
    const btBroadphaseProxy* p0 = o0->getBroadphaseHandle();
    const btBroadphaseProxy* p1 = o1->getBroadphaseHandle();
    if (p0 == nullptr || p1 == nullptr) return nullptr;
    const auto it = m_records.find(pairKey(p0, p1));
    if (it == m_records.end()) return nullptr;
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
    // On a compound's side the compound algorithm's child wrappers may use the record: the mesh triangles kept for
    // the whole compound are a superset of those near any one child.
    auto compound = [](const btCollisionShape* s) { return s->getShapeType() == COMPOUND_SHAPE_PROXYTYPE; };
    if ((child0 && !compound(s0)) || (child1 && !compound(s1))) return nullptr;
    // Compare the objects' shapes and transforms (a child wrapper carries the child's).
    if (s0 != o0->getCollisionShape() || s1 != o1->getCollisionShape()) return nullptr;
    if (!(t0 == o0->getWorldTransform()) || !(t1 == o1->getWorldTransform())) return nullptr;  // moved since
    if (!child0 && !(t0 == w0->getWorldTransform())) return nullptr;
    if (!child1 && !(t1 == w1->getWorldTransform())) return nullptr;
    return &rec.triangles;
}

void PairRecords::forgetProxy(const btBroadphaseProxy* p) {
    for (auto it = m_records.begin(); it != m_records.end();)
        it = it->second.first == p || it->second.second == p ? m_records.erase(it) : std::next(it);
}

}  // namespace cullide::bullet
