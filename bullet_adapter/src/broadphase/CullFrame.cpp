#include "broadphase/CullFrame.h"

#include "broadphase/BulletProxies.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace cullide::bullet {

void updateWorld(CulledObject& c, const btTransform& t) {
    const ShapeTriangles& g = *c.geometry;
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

void CullFrame::build(const std::vector<ProxyPair>& candidates, std::uint64_t step, CullideFrameStats& stats) {
    m_objects.clear();
    m_objectProxy.clear();
    m_marginEntries.clear();
    m_pairs.clear();
    for (const auto& [a, b] : candidates) {
        CulledObject& ca = enter(a, step, stats);
        CulledObject& cb = enter(b, step, stats);
        m_pairs.emplace_back(std::min(ca.cullIndex, cb.cullIndex), std::max(ca.cullIndex, cb.cullIndex));
    }
    std::sort(m_pairs.begin(), m_pairs.end());
    stats.culledObjects = m_objects.size();
    stats.culledPairs = m_pairs.size();
}

/// The object of proxy p in this step's frame (added on first use).
CulledObject& CullFrame::enter(btBroadphaseProxy* p, std::uint64_t step, CullideFrameStats& stats) {
    CulledObject& c = m_culled[p];
    if (c.key == 0) c.key = ++m_nextKey;
    if (c.step == step) return c;
    c.step = step;
    c.cullIndex = static_cast<std::uint32_t>(m_objects.size());
    const btCollisionObject* obj = objectOf(p);
    const btCollisionShape* shape = obj->getCollisionShape();
    // World-space and cached only while it rests: Bullet's static flag alone does not say that (plain
    // btCollisionObjects in a collision world are static-flagged and moved by the application).
    const btTransform& t = obj->getWorldTransform();
    const bool moved = c.seen && !(c.lastFrom == t);
    c.lastFrom = t;
    c.seen = true;
    const bool isStatic = obj->isStaticObject() && !moved;
    Object o;
    MarginEntry entry;
    entry.kind = geometryKindOf(shape);
    entry.motionDisc = double(shape->getAngularMotionDisc());
    if (geometryFor(c, shape)) {
        if (isStatic) {
            // World-space, kept between steps with the culler's static cache (staticKey below).
            updateWorld(c, obj->getWorldTransform());
            o.mesh = &c.world;
            o.staticKey = c.key;
            o.version = c.version;
        } else {
            if (c.worldValid || c.world.vertices.capacity() != 0) {  // a world-space copy from when it rested
                c.world = TriangleMesh{};
                c.worldValid = false;
            }
            // The shape's local mesh and this step's transform: the culler maps the vertices only if the object
            // comes near another one (the same arithmetic as updateWorld, see toTransform). Keyed: the culler keeps
            // its checks in its own frame while it moves.
            c.toWorld = toTransform(obj->getWorldTransform());
            o.mesh = &c.geometry->local;
            o.transform = &c.toWorld;
            if (c.localKey == 0) c.localKey = ++m_nextKey;
            if (c.keyedGeometry.lock() != c.geometry) {
                ++c.localVersion;
                c.keyedGeometry = c.geometry;
            }
            o.staticKey = c.localKey;
            o.version = c.localVersion;
        }
        for (int k = 0; k < 3; ++k)
            entry.coordinate = std::max({entry.coordinate, std::fabs(double(p->m_aabbMin[k])),
                                         std::fabs(double(p->m_aabbMax[k]))});
        ++stats.meshObjects;
        stats.triangles += c.geometry->triangles.size();
    } else {
        entry.kind = GeometryKind::None;
        o.box.min = toVec(p->m_aabbMin);
        o.box.max = toVec(p->m_aabbMax);
    }
    switch (entry.kind) {
        case GeometryKind::GImpactMesh:
        case GeometryKind::Compound: entry.margin = double(triangleMarginOf(shape)); break;
        default: entry.margin = double(shape->getMargin()); break;
    }
    m_objects.push_back(o);
    m_objectProxy.push_back(p);
    m_marginEntries.push_back(entry);
    return c;
}

/// A shape's content hash, computed once per step however many proxies share the shape.
std::uint64_t CullFrame::sourceHashThisStep(const btCollisionShape* shape) {
    const auto [it, added] = m_hashThisStep.emplace(shape, 0);
    if (added) it->second = sourceHashOf(shape);
    return it->second;
}

/// The shape's triangles: the object's own while they still match the shape's content, else those of another
/// object with the same shape, else built now (and shared from then on).
std::shared_ptr<ShapeTriangles> CullFrame::geometryFor(CulledObject& c, const btCollisionShape* shape) {
    if (shape == nullptr || geometryKindOf(shape) == GeometryKind::None) {
        c.geometry.reset();
        c.worldValid = false;
        return nullptr;
    }
    const std::uint64_t hash = sourceHashThisStep(shape);
    if (c.geometry && stillMatches(*c.geometry, shape, hash)) return c.geometry;
    c.worldValid = false;
    auto it = m_shapes.find(shape);
    if (it != m_shapes.end()) {
        if (auto shared = it->second.lock(); shared && stillMatches(*shared, shape, hash)) {
            c.geometry = shared;
            return shared;
        }
    }
    auto built = buildShapeTriangles(shape, hash);
    if (built)
        m_shapes[shape] = built;
    else
        m_shapes.erase(shape);
    c.geometry = built;
    return built;
}

void CullFrame::invalidateShape(const btCollisionShape* shape) {
    m_shapes.erase(shape);
    for (auto& [proxy, c] : m_culled) {
        if (c.geometry && c.geometry->shape == shape) {
            c.geometry.reset();
            c.worldValid = false;
        }
    }
}

namespace {
template <typename T>
std::size_t heapBytes(const std::vector<T>& v) {
    return v.capacity() * sizeof(T);
}
std::size_t heapBytes(const TriangleMesh& m) { return heapBytes(m.vertices) + heapBytes(m.triangles); }
}  // namespace

CullideMemoryStats CullFrame::memory() const {
    CullideMemoryStats m;
    std::unordered_set<const ShapeTriangles*> geometries;  // each held once, however many objects point to it
    for (const auto& [proxy, c] : m_culled) {
        ++m.objects;
        m.objectBytes += sizeof(proxy) + sizeof(c) + heapBytes(c.world);
        m.worldCopies += c.world.triangles.empty() ? 0 : 1;
        const ShapeTriangles* g = c.geometry.get();
        if (g == nullptr || !geometries.insert(g).second) continue;
        ++m.shapes;
        m.sharedGeometryBytes += sizeof(ShapeTriangles) + heapBytes(g->vertices) + heapBytes(g->triangles) +
                                 heapBytes(g->refs) + heapBytes(g->local);
    }
    return m;
}

void CullFrame::clear() {
    m_culled.clear();
    m_shapes.clear();
}

}  // namespace cullide::bullet
