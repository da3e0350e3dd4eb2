// Where the meshes that are not static lie in the device's position, index and spatial-order arrays
// (GpuGeometry), after the resident region of the static ones: a place per object's mesh, kept across the uploads of
// a frame's clusters and across frames while its counts stay. A mesh's indices and order are global (from its place),
// so they stay the same, and are not sent again, while other meshes come and go around it; only what moves or
// deforms is sent. Places free up after kKeepFrames frames unused, and all are placed anew when freed ones outnumber
// the used (or the region grew into them).
#pragma once

#include "cullide/Types.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>

namespace cullide {

class MeshSlots {
public:
    /// Starts a frame (of any number of uploads, one per cluster): places age by frames.
    void beginFrame() { ++m_frame; }

    /// Starts an upload whose resident region ends at (`regionVertices`, `regionTriangles`): drops the places unused
    /// for kKeepFrames frames, and starts over where the region reaches into the places or the dropped space
    /// outnumbers the used. Returns whether it started over.
    bool beginUpload(std::size_t regionVertices, std::size_t regionTriangles);

    struct Slot {
        std::uint32_t baseVertex = 0;
        std::uint32_t baseTriangle = 0;
    };
    /// The place of object `object`'s mesh `mesh` (found by both and its counts). The meshes mapped on the device
    /// (`mapped`) have their vertices after every other's (plainVertexEnd()): place the others first in an upload, as a
    /// place for them may move the mapped ones'.
    Slot place(std::uint32_t object, const TriangleMesh& mesh, bool mapped);

    /// Where the places of the meshes that are not mapped end (the mapped ones' start at or after it), and every
    /// place's triangles.
    std::size_t plainVertexEnd() const { return m_plainEnd; }
    std::size_t triangleEnd() const { return m_triangleEnd; }

private:
    struct Key {
        std::uint32_t object;
        const TriangleMesh* mesh;
        bool mapped;
        bool operator==(const Key& o) const { return object == o.object && mesh == o.mesh && mapped == o.mapped; }
    };
    struct KeyHash {
        std::size_t operator()(const Key& k) const {
            return std::hash<const void*>()(k.mesh) ^ (std::size_t{k.object} * 0x9E3779B97F4A7C15ull) ^ k.mapped;
        }
    };
    struct Entry {
        Slot slot;
        std::uint32_t vertices = 0;
        std::uint32_t triangles = 0;
        std::uint64_t lastFrame = 0;
    };
    static constexpr std::uint64_t kKeepFrames = 64;

    void startOver(std::size_t regionVertices, std::size_t regionTriangles);

    std::unordered_map<Key, Entry, KeyHash> m_entries;
    std::uint64_t m_frame = 0;
    std::size_t m_vertexStart = 0;    ///< where the places' vertices start (the region ends before)
    std::size_t m_triangleStart = 0;  ///< where their triangles start
    std::size_t m_plainEnd = 0;       ///< the plain meshes' vertices placed so far end here
    std::size_t m_mappedBase = 0;     ///< the mapped meshes' vertices start here (room for plain ones before)
    std::size_t m_mappedEnd = 0;
    std::size_t m_triangleEnd = 0;
    bool m_started = false;
};

}  // namespace cullide
