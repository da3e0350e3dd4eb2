#include "ClusterGeometry.h"

#include "FloatRounding.h"
#include "bindings.h"
#include "KeptCapacity.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace cullide {

namespace {

/// Sets values[at + i] = value(i) for i < n, reading first and writing only from the first value that differs: returns
/// that value's place in `values` (ClusterGeometry's kNone where none does).
template <typename Value>
std::size_t writeFromFirstDifference(std::vector<std::uint32_t>& values, std::size_t at, std::size_t n,
                                     const Value& value) {
    std::size_t i = 0;
    while (i < n && values[at + i] == value(i)) ++i;
    if (i == n) return static_cast<std::size_t>(-1);
    for (std::size_t k = i; k < n; ++k) values[at + k] = value(k);
    return at + i;
}

}  // namespace

void ClusterGeometry::upload(const FrameState& frame, const Cluster& cluster, double margin, PruningBackend& backend,
                             TaskPool& pool, Stats& stats) {
    placeMeshes(frame, cluster);
    // Whatever the arrays already hold is what the device holds (up to the last upload's size): only what changes
    // from the first changed value on is sent again — a mesh whose topology stays the same keeps its indices there,
    // a mesh at rest its positions.
    m_changed.assign(m_written.size(), Changed{});
    pool.parallelFor(m_written.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) m_changed[i] = writeMesh(frame, m_written[i]);
    });
    m_geometry.keptPositions = m_geometry.positions.size();
    m_geometry.keptIndices = m_geometry.indices.size();
    m_geometry.keptOrdered = m_geometry.ordered.size();
    m_geometry.keptLocal = m_localStartedOver ? 0 : m_geometry.local.size();
    for (const Changed& c : m_changed) {
        m_geometry.keptPositions = std::min(m_geometry.keptPositions, c.firstPosition);
        m_geometry.keptIndices = std::min(m_geometry.keptIndices, c.firstIndex);
        m_geometry.keptOrdered = std::min(m_geometry.keptOrdered, c.firstOrdered);
        m_geometry.keptLocal = std::min(m_geometry.keptLocal, c.firstLocal);
    }
    m_geometry.origin = m_origin;
    m_geometry.mapped.clear();
    for (const MeshSlot& slot : m_written) {
        if (!slot.mapped) continue;
        const Object& input = (*frame.inputs)[slot.object];
        m_geometry.mapped.push_back(MappedMesh{*input.transform, slot.localBase, slot.baseVertex,
                                               static_cast<std::uint32_t>(input.mesh->vertices.size())});
    }
    m_geometry.boxes.clear();
    m_geometry.coordinateBound = 0.0;
    m_objectBox.assign(frame.valid.size(), 0);
    for (std::uint32_t o : cluster.objects) m_objectBox[o] = appendBox(frame.valid[o].box);
    appendGroupBoxes(frame, cluster, margin);
    backend.upload(m_geometry, stats);
}

/// The groups' boxes (FrameState::allGroups of the cluster's meshes): first every group's of the static meshes, in
/// object order, sent, so that they stay where the device holds them while other meshes move; then every group's of
/// the other meshes, built on the device from their positions (GpuGeometry::builtRanges: a range of the spatial order
/// each, which changes only with the layout). Neither depends on which groups the box pre-pass keeps, and each
/// object's boxes lie together (firstGroupBox).
void ClusterGeometry::appendGroupBoxes(const FrameState& frame, const Cluster& cluster, double margin) {
    const std::vector<Group>& all = frame.allGroups;
    constexpr std::uint32_t kNone = 0xFFFFFFFFu, kBuilt = 0x80000000u;  // kBuilt | its place among the built boxes
    m_firstGroupBox.assign(frame.valid.size(), kNone);
    m_geometry.builtRanges.clear();
    m_geometry.builtInflate = floatUp(0.5 * margin);
    const auto before = [](const Group& a, std::uint32_t object) { return a.object < object; };
    for (const bool built : {false, true}) {
        for (std::uint32_t o : cluster.objects) {
            const bool isStatic = !frame.statics.entry.empty() && frame.statics.entry[o] != nullptr;
            auto g = std::lower_bound(all.begin(), all.end(), o, before);
            if (isStatic == built || g == all.end() || g->object != o) continue;
            m_firstGroupBox[o] = built ? kBuilt | static_cast<std::uint32_t>(m_geometry.builtRanges.size() / 2)
                                       : static_cast<std::uint32_t>(m_geometry.boxes.size() / 6);
            for (; g != all.end() && g->object == o; ++g) {
                if (!built) {
                    appendBox(g->box);
                    continue;
                }
                m_geometry.builtRanges.push_back(m_baseTriangle[o] + g->first);
                m_geometry.builtRanges.push_back(g->count);
            }
        }
    }
    const auto firstBuilt = static_cast<std::uint32_t>(m_geometry.boxes.size() / 6);  // the built ones follow
    for (std::uint32_t& box : m_firstGroupBox)
        if (box != kNone && (box & kBuilt) != 0) box = firstBuilt + (box & ~kBuilt);
}

namespace {

/// Whether object o's mesh goes in its own frame, mapped by the backend: it came with a transform and is not static
/// (a static mesh is written once in world space).
bool isMapped(const FrameState& frame, std::uint32_t o) {
    return frame.inputs != nullptr && (*frame.inputs)[o].transform != nullptr && frame.statics.entry[o] == nullptr;
}

}  // namespace

/// The origin (ResidentRegion::fit), then static meshes where the region holds them (or appended to it), every other
/// mesh at its place after the region (MeshSlots: the mapped ones' vertices after the others'); m_written lists what
/// must be written this upload.
void ClusterGeometry::placeMeshes(const FrameState& frame, const Cluster& cluster) {
    Aabb all;
    std::size_t staticTriangles = 0;
    for (std::uint32_t o : cluster.objects) {
        all.grow(frame.valid[o].box);
        if (frame.isMesh(o) && frame.statics.entry[o] != nullptr) staticTriangles += frame.meshOf(o).triangles.size();
    }
    const Vec3 centre = all.isEmpty() ? Vec3::Zero() : Vec3(0.5 * (all.min + all.max));
    const double extent = all.isEmpty() ? 0.0 : all.extent().maxCoeff();
    m_origin = m_region.fit(centre, extent, staticTriangles);
    m_baseTriangle.assign(frame.valid.size(), 0);
    m_written.clear();
    for (std::uint32_t o : cluster.objects) {
        StaticEntry* e = frame.statics.entry[o];
        if (!frame.isMesh(o) || e == nullptr) continue;
        const TriangleMesh& mesh = frame.meshOf(o);
        const std::uint64_t order = frame.orderSerial.empty() ? 0 : frame.orderSerial[o];
        const ResidentRegion::Place p = m_region.place(*e, mesh.vertices.size(), mesh.triangles.size(), order);
        if (p.appended) m_written.push_back({o, p.baseVertex, p.baseTriangle});
        m_baseTriangle[o] = p.baseTriangle;
    }
    m_slots.beginUpload(m_region.vertices(), m_region.triangles());
    m_localStartedOver = m_mappedVertices.beginUpload(m_geometry.local);
    for (const bool mapped : {false, true}) {  // the plain meshes first: a place for one may move the mapped ones'
        for (std::uint32_t o : cluster.objects) {
            if (!frame.isMesh(o) || frame.statics.entry[o] != nullptr || isMapped(frame, o) != mapped) continue;
            const TriangleMesh& mesh = frame.meshOf(o);
            const MeshSlots::Slot place = m_slots.place(o, mesh, mapped);
            MeshSlot slot{o, place.baseVertex, place.baseTriangle, mapped};
            if (mapped) {
                const MappedVertices::Slot local = m_mappedVertices.place(*(*frame.inputs)[o].mesh, m_geometry.local);
                slot.localBase = local.base;
                slot.writeLocal = !local.placedBefore;
            }
            m_written.push_back(slot);
            m_baseTriangle[o] = place.baseTriangle;
        }
    }
    resizeKeeping(m_geometry.positions, 3 * m_slots.plainVertexEnd());
    resizeKeeping(m_geometry.indices, 3 * m_slots.triangleEnd());
    resizeKeeping(m_geometry.ordered, m_slots.triangleEnd());
}

/// A mesh's vertices (world positions as the device holds them, or a mapped mesh's own) and its triangles' global
/// vertex indices, each compared with what the arrays held (bit for bit: -0 and +0 differ) before it is written.
ClusterGeometry::Changed ClusterGeometry::writeMesh(const FrameState& frame, const MeshSlot& slot) {
    Changed changed;
    const TriangleMesh& mesh = frame.meshOf(slot.object);
    if (!slot.mapped) {
        writePositions(mesh, slot, changed);
    } else if (slot.writeLocal) {
        const std::size_t first = MappedVertices::write(*(*frame.inputs)[slot.object].mesh, slot.localBase,
                                                        m_geometry.local);
        if (first < m_geometry.local.size()) changed.firstLocal = first;
    }
    // Read first, write from the first difference on: a mesh whose topology stays the same costs a read of its
    // indices and order, no store.
    changed.firstIndex = writeFromFirstDifference(
        m_geometry.indices, 3 * std::size_t{slot.baseTriangle}, 3 * mesh.triangles.size(),
        [&](std::size_t i) { return slot.baseVertex + mesh.triangles[i / 3][i % 3]; });
    const std::vector<std::uint32_t>* order = frame.order.empty() ? nullptr : frame.order[slot.object];
    changed.firstOrdered = writeFromFirstDifference(
        m_geometry.ordered, slot.baseTriangle, mesh.triangles.size(), [&](std::size_t k) {
            return slot.baseTriangle + (order != nullptr ? (*order)[k] : static_cast<std::uint32_t>(k));
        });
    return changed;
}

void ClusterGeometry::writePositions(const TriangleMesh& world, const MeshSlot& slot, Changed& changed) {
    float* out = m_geometry.positions.data() + 3 * std::size_t{slot.baseVertex};
    const std::size_t n = world.vertices.size();
    std::size_t v = 0;
    float f[3];
    for (; v < n; ++v) {  // read first: a mesh at rest costs no store
        devicePosition(world.vertices[v], m_origin, f);
        if (std::memcmp(out + 3 * v, f, sizeof f) != 0) break;
    }
    if (v == n) return;
    int a = 0;
    while (std::memcmp(out + 3 * v + a, f + a, sizeof(float)) == 0) ++a;
    changed.firstPosition = 3 * (std::size_t{slot.baseVertex} + v) + static_cast<std::size_t>(a);
    std::memcpy(out + 3 * v, f, sizeof f);
    for (++v; v < n; ++v) devicePosition(world.vertices[v], m_origin, out + 3 * v);
}

std::vector<float> allPositions(const GpuGeometry& geometry) {
    std::vector<float> all = geometry.positions;
    all.resize(3 * geometry.vertexCount(), 0.0f);
    for (const MappedMesh& m : geometry.mapped) {
        for (std::uint32_t v = 0; v < m.count; ++v) {
            const double* p = &geometry.local[3 * (std::size_t{m.localBase} + v)];
            devicePosition(transformPoint(m.transform, Vec3(p[0], p[1], p[2])), geometry.origin,
                           &all[3 * (std::size_t{m.baseVertex} + v)]);
        }
    }
    return all;
}

std::vector<float> allBoxes(const GpuGeometry& geometry, const std::vector<float>& positions) {
    std::vector<float> all = geometry.boxes;
    const auto vertex = [&](std::uint32_t triangle, int corner) {
        return &positions.at(3 * std::size_t{geometry.indices.at(3 * std::size_t{triangle} + corner)});
    };
    for (std::size_t b = 0; b + 1 < geometry.builtRanges.size(); b += 2) {
        const std::uint32_t first = geometry.builtRanges[b], count = geometry.builtRanges[b + 1];
        float lo[3], hi[3];
        std::copy_n(vertex(geometry.ordered.at(first), 0), 3, lo);
        std::copy_n(lo, 3, hi);
        for (std::uint32_t k = 0; k < count; ++k) {
            for (int c = 0; c < 3; ++c) {
                const float* p = vertex(geometry.ordered.at(first + k), c);
                for (int a = 0; a < 3; ++a) {
                    if (p[a] < lo[a]) lo[a] = p[a];
                    if (p[a] > hi[a]) hi[a] = p[a];
                }
            }
        }
        for (int a = 0; a < 3; ++a) all.push_back(lo[a] - geometry.builtInflate);
        for (int a = 0; a < 3; ++a) all.push_back(hi[a] + geometry.builtInflate);
    }
    return all;
}

float ClusterGeometry::prepassSlack(double grow) const {
    const double bound = m_geometry.coordinateBound;
    return floatUp(grow + std::ldexp(bound, -22) + std::ldexp(m_origin.cwiseAbs().maxCoeff() + bound, -50));
}

std::uint32_t ClusterGeometry::appendBox(const Aabb& worldBox) {
    const Aabb r = relative(worldBox);
    for (int a = 0; a < 3; ++a) m_geometry.boxes.push_back(floatDown(r.min[a]));
    for (int a = 0; a < 3; ++a) m_geometry.boxes.push_back(floatUp(r.max[a]));
    m_geometry.coordinateBound =
        std::max({m_geometry.coordinateBound, r.min.cwiseAbs().maxCoeff(), r.max.cwiseAbs().maxCoeff()});
    return static_cast<std::uint32_t>(m_geometry.boxes.size() / 6 - 1);
}

}  // namespace cullide
