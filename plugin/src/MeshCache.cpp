#include "MeshCache.h"

#include <algorithm>
#include <iterator>

namespace cullide {
namespace {

/// The cached world boxes of an entry hold for this object's transform (bit for bit; NaNs never match).
bool sameTransform(const StaticEntry& e, const Transform* t) {
    if (t == nullptr) return !e.transformed;
    return e.transformed && e.transform.linear == t->linear && e.transform.translation == t->translation;
}

/// The entry's own-frame part holds for this object: the same mesh, and a transform both times or neither.
bool ownFrameHolds(const StaticEntry& e, const Object& o) {
    return e.checked && e.version == o.version && e.vertices == o.mesh->vertices.size() &&
           e.triangles == o.mesh->triangles.size() && e.transformed == (o.transform != nullptr);
}

}  // namespace

void StaticEntry::dropWorldPart() {
    boxesReady = false;
    boxes = {};
    treeReady = false;
    tree = BoxTree{};
    regionEpoch = 0;
    regionOrder = 0;
    regionBaseTriangle = 0;
}

void StaticMeshCache::lookUp(const std::vector<Object>& objects, StaticLookup& lookup) {
    ++m_frame;
    for (auto it = m_entries.begin(); it != m_entries.end();)
        it = it->second.lastFrame + kKeepFrames < m_frame ? m_entries.erase(it) : std::next(it);
    lookup.entry.assign(objects.size(), nullptr);
    lookup.moving.assign(objects.size(), nullptr);
    lookup.known.assign(objects.size(), 0);
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Object& o = objects[i];
        if (o.mesh == nullptr || o.staticKey == 0) continue;
        StaticEntry& e = m_entries[o.staticKey];
        if (e.lastFrame == m_frame) continue;  // a key used twice in one frame: the second is not cached
        const bool own = ownFrameHolds(e, o);
        if (!own) {
            e = StaticEntry{};
            e.version = o.version;
            e.vertices = o.mesh->vertices.size();
            e.triangles = o.mesh->triangles.size();
            e.transformed = o.transform != nullptr;
        }
        e.lastFrame = m_frame;
        lookup.known[i] = e.checked ? 1 : 0;
        // A mesh with a transform is static geometry once it keeps its transform from one frame to the next; until
        // then (first seen, or moved) only its own-frame part is kept: a moving body pays for no world part.
        if (o.transform != nullptr && (!own || !sameTransform(e, o.transform))) {
            e.dropWorldPart();  // its transform stays that of its validation until merge places it by this frame's
            lookup.moving[i] = &e;
        } else {
            lookup.entry[i] = &e;
        }
    }
}

namespace {

/// A moving mesh's validation under this frame's transform, from its own frame's (kept in the entry, which then
/// holds this transform's).
void placeMoving(StaticEntry& e, const Transform& t, double margin) {
    e.transform = t;
    if (!e.valid.localChecked) return;  // rejected in its own frame: so it is under any transform
    const char* error = placeTransformed(t, margin, e.valid);
    e.error = error != nullptr ? error : "";
}

}  // namespace

void StaticMeshCache::merge(const std::vector<Object>& objects, const StaticLookup& lookup, double margin,
                            std::vector<ValidatedObject>& valid, Result& result, Stats& stats) {
    bool added = false;
    for (std::size_t i = 0; i < lookup.entry.size(); ++i) {
        StaticEntry* e = lookup.entry[i] != nullptr ? lookup.entry[i] : lookup.moving[i];
        if (e == nullptr) continue;
        const auto id = static_cast<std::uint32_t>(i);
        if (!lookup.known[i]) {  // validated this frame: kept
            e->checked = true;
            e->valid = valid[i];
            if (lookup.moving[i] != nullptr) e->transform = *objects[i].transform;
            for (const ObjectDiagnostic& d : result.rejected)
                if (d.object == id) e->error = d.message;
            continue;
        }
        const bool moving = lookup.moving[i] != nullptr;
        if (moving) placeMoving(*e, *objects[i].transform, margin);
        valid[i] = e->valid;
        if (!e->error.empty()) {
            result.rejected.push_back({id, e->error});
            added = true;
        }
        ++(moving ? stats.movingObjectsReused : stats.staticObjectsReused);
    }
    if (added)
        std::stable_sort(result.rejected.begin(), result.rejected.end(),
                         [](const ObjectDiagnostic& a, const ObjectDiagnostic& b) { return a.object < b.object; });
}

Vec3 ResidentRegion::fit(const Vec3& centre, double extent, std::size_t staticTriangles) {
    const bool keep = m_epoch != 0 && (centre - m_origin).cwiseAbs().maxCoeff() <= 0.5 * m_extent &&
                      extent <= 2.0 * m_extent && extent >= 0.25 * m_extent &&
                      m_triangles <= 2 * staticTriangles + 65536;
    if (!keep) {
        ++m_epoch;
        m_origin = centre;
        m_extent = std::max(extent, 1e-300);
        m_vertices = 0;
        m_triangles = 0;
    }
    return m_origin;
}

ResidentRegion::Place ResidentRegion::place(StaticEntry& entry, std::size_t vertices, std::size_t triangles,
                                            std::uint64_t order) {
    Place p;
    if (entry.regionEpoch != m_epoch || entry.regionOrder != order) {  // another order: the old place goes stale
        p.appended = true;
        p.baseVertex = static_cast<std::uint32_t>(m_vertices);
        entry.regionEpoch = m_epoch;
        entry.regionOrder = order;
        entry.regionBaseTriangle = static_cast<std::uint32_t>(m_triangles);
        m_vertices += vertices;
        m_triangles += triangles;
    }
    p.baseTriangle = entry.regionBaseTriangle;
    return p;
}

}  // namespace cullide
