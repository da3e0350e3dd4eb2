#include "MeshSlots.h"

#include <algorithm>

namespace cullide {

void MeshSlots::startOver(std::size_t regionVertices, std::size_t regionTriangles) {
    m_entries.clear();
    m_vertexStart = m_plainEnd = m_mappedBase = m_mappedEnd = regionVertices;
    m_triangleStart = m_triangleEnd = regionTriangles;
    m_started = true;
}

bool MeshSlots::beginUpload(std::size_t regionVertices, std::size_t regionTriangles) {
    if (!m_started || regionVertices > m_vertexStart || regionTriangles > m_triangleStart) {
        startOver(regionVertices, regionTriangles);
        return true;
    }
    std::size_t live = 0;
    for (auto it = m_entries.begin(); it != m_entries.end();) {
        if (m_frame - it->second.lastFrame > kKeepFrames) {
            it = m_entries.erase(it);
        } else {
            live += std::size_t{it->second.vertices} + it->second.triangles;
            ++it;
        }
    }
    const std::size_t used = (m_mappedEnd - m_vertexStart) + (m_triangleEnd - m_triangleStart);
    if (used <= 2 * live + 65536) return false;
    startOver(regionVertices, regionTriangles);  // mostly freed places: the live ones are placed again
    return true;
}

MeshSlots::Slot MeshSlots::place(std::uint32_t object, const TriangleMesh& mesh, bool mapped) {
    const auto vertices = static_cast<std::uint32_t>(mesh.vertices.size());
    const auto triangles = static_cast<std::uint32_t>(mesh.triangles.size());
    auto [it, added] = m_entries.try_emplace(Key{object, &mesh, mapped});
    Entry& e = it->second;
    if (added || e.vertices != vertices || e.triangles != triangles) {  // a new place (counts changed: a new mesh)
        if (!mapped && m_plainEnd + vertices > m_mappedBase) {
            // Room for the plain meshes grows by half again at least, and the mapped ones are placed anew after it.
            const std::size_t room = m_mappedBase - m_vertexStart;
            m_mappedBase = m_vertexStart + std::max({room + room / 2, m_plainEnd + vertices - m_vertexStart,
                                                     std::size_t{1024}});
            m_mappedEnd = m_mappedBase;
            for (auto m = m_entries.begin(); m != m_entries.end();)
                m = m->first.mapped ? m_entries.erase(m) : std::next(m);
            it = m_entries.find(Key{object, &mesh, mapped});
        }
        Entry& placed = it->second;
        std::size_t& end = mapped ? m_mappedEnd : m_plainEnd;
        placed.slot.baseVertex = static_cast<std::uint32_t>(end);
        placed.slot.baseTriangle = static_cast<std::uint32_t>(m_triangleEnd);
        placed.vertices = vertices;
        placed.triangles = triangles;
        end += vertices;
        m_triangleEnd += triangles;
    }
    it->second.lastFrame = m_frame;
    return it->second.slot;
}

}  // namespace cullide
