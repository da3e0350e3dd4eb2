// The device's copy of one cluster (FrameState.h): positions and indices of its meshes and the boxes of its objects
// and groups, relative to an origin near the cluster's centre, in float. Static meshes sit in the resident region at
// the front of the buffers and are sent once (MeshCache.h); the other meshes keep their places after it across uploads
// and frames (MeshSlots.h), and of them only what changed since the last upload is sent again (a deforming mesh's
// positions, not its indices, whatever other meshes come and go). A mesh that came with a transform goes in
// its own frame, mapped by the backend (MappedMesh): while it moves rigidly only its transform is sent.
#pragma once

#include "FrameState.h"
#include "MappedVertices.h"
#include "MeshSlots.h"
#include "MeshCache.h"
#include "PruningBackend.h"
#include "cullide/TaskPool.h"

#include <cstdint>
#include <vector>

namespace cullide {

class ClusterGeometry {
public:
    /// Writes the cluster's geometry relative to its origin (float precision is spent on the cluster, not on its
    /// offset) and hands it to `backend`. Boxes are rounded outwards to float; the groups of the meshes that are not
    /// static are built on the device, grown by `margin` / 2 (GpuGeometry::builtRanges).
    void upload(const FrameState& frame, const Cluster& cluster, double margin, PruningBackend& backend,
                TaskPool& pool, Stats& stats);

    /// Starts a frame: what the device keeps between frames ages by frames, not by uploads (one per cluster).
    void beginFrame() {
        m_mappedVertices.beginFrame();
        m_slots.beginFrame();
    }

    /// Of the last upload: where object o's triangles start in the index buffer (and in the spatial orders), its
    /// box's index, and its first group's box (of FrameState::allGroups: its k-th group's is firstGroupBox(o) + k).
    std::uint32_t baseTriangle(std::uint32_t object) const { return m_baseTriangle[object]; }
    std::uint32_t objectBox(std::uint32_t object) const { return m_objectBox[object]; }
    std::uint32_t firstGroupBox(std::uint32_t object) const { return m_firstGroupBox[object]; }
    /// The largest |coordinate| uploaded (GpuGeometry::coordinateBound), for the views' error bounds.
    double coordinateBound() const { return m_geometry.coordinateBound; }
    /// How far a box pre-pass on the device must grow the boxes it compares, beyond `grow`, to keep whatever the CPU's
    /// keeps in double: the float rounding of the positions and boxes as uploaded (2^-22 of the largest coordinate,
    /// as fitView allows) and the double rounding of world - origin. Rounded up to float.
    float prepassSlack(double grow) const;
    /// The last upload's origin (world).
    const Vec3& origin() const { return m_origin; }
    /// A world box relative to the upload's origin.
    Aabb relative(const Aabb& worldBox) const { return {worldBox.min - m_origin, worldBox.max - m_origin}; }

private:
    /// Where a mesh goes in the position (or, mapped, the local) and index arrays.
    struct MeshSlot {
        std::uint32_t object;
        std::uint32_t baseVertex;
        std::uint32_t baseTriangle;
        bool mapped = false;
        std::uint32_t localBase = 0;  ///< mapped: its first vertex in the local array
        bool writeLocal = false;      ///< mapped: the first object of the upload with its mesh (it writes the slot)
    };
    /// Where a written mesh first differs from what the arrays held (kNone: nowhere).
    struct Changed {
        static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
        std::size_t firstPosition = kNone;  ///< in floats
        std::size_t firstIndex = kNone;
        std::size_t firstLocal = kNone;  ///< in doubles
        std::size_t firstOrdered = kNone;
    };
    void placeMeshes(const FrameState& frame, const Cluster& cluster);
    Changed writeMesh(const FrameState& frame, const MeshSlot& slot);
    void writePositions(const TriangleMesh& world, const MeshSlot& slot, Changed& changed);
    std::uint32_t appendBox(const Aabb& worldBox);
    void appendGroupBoxes(const FrameState& frame, const Cluster& cluster, double margin);

    ResidentRegion m_region;
    MeshSlots m_slots;  ///< where the other meshes lie after the region
    MappedVertices m_mappedVertices;  ///< the slots of m_geometry.local
    bool m_localStartedOver = false;  ///< this upload: nothing of m_geometry.local is on the device
    GpuGeometry m_geometry;  ///< the backend reads it until the next upload
    Vec3 m_origin = Vec3::Zero();
    std::vector<std::uint32_t> m_baseTriangle;
    std::vector<std::uint32_t> m_objectBox;
    std::vector<std::uint32_t> m_firstGroupBox;  ///< per object
    std::vector<MeshSlot> m_written;  ///< the meshes written this upload
    std::vector<Changed> m_changed;   ///< per written mesh
};

}  // namespace cullide
