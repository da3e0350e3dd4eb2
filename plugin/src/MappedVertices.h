// The vertices of the meshes that come with a transform (Object::transform), in their own frames, as the device
// holds them (GpuGeometry::local): one slot per mesh, shared by every object that uses the mesh and kept across the
// uploads of a frame's clusters and across frames, so that a rigid mesh's vertices are sent once and only its
// transform with each upload.
#pragma once

#include "cullide/Types.h"

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace cullide {

/// The slots of `values` (xyz per vertex, GpuGeometry::local), which the caller keeps.
class MappedVertices {
public:
    /// Starts a frame (of any number of uploads, one per cluster): slots age by frames.
    void beginFrame() { ++m_frame; }

    /// Starts an upload: drops the slots no upload used for kKeepFrames frames, and starts over (`values` cleared,
    /// every slot placed and sent again) when those dropped hold more than the slots in use. Returns whether it
    /// started over.
    bool beginUpload(std::vector<double>& values);

    /// The slot of `mesh` (found by its address and vertex count: its content is compared by write()): where its
    /// first vertex is in values(), and whether this upload placed it already (another object with the same mesh).
    struct Slot {
        std::uint32_t base = 0;
        bool placedBefore = false;
    };
    Slot place(const TriangleMesh& mesh, std::vector<double>& values);

    /// Writes `mesh`'s vertices at `base` (as placed), comparing each value with what was there bit for bit. Returns
    /// the index into `values` of the first that differed (values.size() when none did). Meshes of different slots
    /// may be written in parallel.
    static std::size_t write(const TriangleMesh& mesh, std::uint32_t base, std::vector<double>& values);

private:
    struct Entry {
        std::uint32_t base = 0;
        std::uint32_t count = 0;
        std::uint64_t lastUpload = 0;
        std::uint64_t lastFrame = 0;
    };
    static constexpr std::uint64_t kKeepFrames = 64;

    std::unordered_map<const TriangleMesh*, Entry> m_slots;
    std::uint64_t m_upload = 0;
    std::uint64_t m_frame = 0;
};

}  // namespace cullide
