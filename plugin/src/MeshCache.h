// What the culler keeps of keyed meshes (Object::staticKey) between frames: for a static one, its validation,
// triangle boxes and box tree (StaticMeshCache) and its place in the device's resident region, sent once
// (ResidentRegion); for one whose transform changes, what it derives in the mesh's own frame (its validation and
// its groups' boxes).
#pragma once

#include "FrameObjects.h"
#include "exact/BoxTree.h"
#include "cullide/Object.h"
#include "cullide/Result.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace cullide {

/// One keyed mesh as the culler keeps it. Its own-frame part holds while (version, vertex count, triangle count,
/// whether it has a transform) stay the same; its world part (boxes, tree, place in the region) while the transform
/// does too.
struct StaticEntry {
    std::uint64_t version = 0;
    std::size_t vertices = 0;
    std::size_t triangles = 0;
    bool transformed = false;
    Transform transform;  ///< when transformed: the one `valid` was placed by
    bool checked = false;
    ValidatedObject valid;  ///< for the last transform (with a transform: localChecked and localBox hold for any)
    std::string error;  ///< the rejection message, if it was rejected
    /// The box of each group of k triangles of the mesh's spatial order (that of serial groupOrder, TriangleOrders) in
    /// its own frame (not inflated; k = groupSize), for the frames its transform changes.
    std::uint32_t groupSize = 0;
    std::uint64_t groupOrder = 0;
    std::vector<Aabb> localGroupBoxes;
    bool boxesReady = false;
    std::vector<Aabb> boxes;  ///< every triangle's world box, inflated by margin / 2 (when boxesReady)
    bool treeReady = false;
    BoxTree tree;  ///< the CPU path's tree of every triangle (MeshTrees; when treeReady)
    std::uint64_t lastFrame = 0;
    std::uint64_t regionEpoch = 0;  ///< == ResidentRegion::epoch(): its triangles are in the device's region
    std::uint64_t regionOrder = 0;  ///< the serial of the spatial order written with them (TriangleOrders)
    std::uint32_t regionBaseTriangle = 0;

    /// A mesh that moved: its world part (boxes, tree, place in the region) starts over, its own-frame part stays.
    void dropWorldPart();
};

/// The frame's view of the cache, per object.
struct StaticLookup {
    /// A static mesh this frame: keyed, in world space or with the transform it had in its last frame. Null: not
    /// keyed, its key was already used this frame, or it is `moving`.
    std::vector<StaticEntry*> entry;
    /// A keyed mesh with a transform, first seen or with another transform than in its last frame (a rigid body in
    /// motion): this frame it is culled as an unkeyed one, except for what holds in its own frame (validation, group
    /// boxes), kept. Null otherwise.
    std::vector<StaticEntry*> moving;
    std::vector<std::uint8_t> known;  ///< 1: validated in an earlier frame (validateObjects skips it)
};

class StaticMeshCache {
public:
    /// Entries unused for this many frames are dropped (a static object far from every moving one is not handed
    /// to the culler by the adapter; it comes back when something approaches).
    static constexpr std::uint64_t kKeepFrames = 240;

    /// Starts a frame: drops stale entries and finds (or makes) each keyed object's entry. An entry whose mesh
    /// version or sizes changed starts over; one whose transform alone changed keeps its own-frame part (moving). A
    /// mesh with a transform is static from the second frame in a row with the same transform.
    void lookUp(const std::vector<Object>& objects, StaticLookup& lookup);

    /// After validateObjects (which skipped the known objects): known entries' validation into the frame (a moving
    /// one's placed by this frame's transform, placeTransformed; rejections into `result.rejected`, kept sorted by
    /// object), new entries' validation into the cache.
    static void merge(const std::vector<Object>& objects, const StaticLookup& lookup, double margin,
                      std::vector<ValidatedObject>& valid, Result& result, Stats& stats);

    std::size_t size() const { return m_entries.size(); }

private:
    std::unordered_map<std::uint64_t, StaticEntry> m_entries;  ///< by Object::staticKey
    std::uint64_t m_frame = 0;
};

/// The front of the device's position and index buffers, where static meshes are written once and stay while the
/// cluster uploaded each frame stays near the region's origin: within half the region's extent, between a quarter
/// and twice as large, and no more than half of the region stale. Otherwise the region starts over at the new
/// cluster's centre (a new epoch: every static mesh is written again).
class ResidentRegion {
public:
    /// Keeps or restarts the region for a cluster with box centre `centre` and largest side `extent` holding
    /// `staticTriangles` static triangles. Returns the origin the cluster's coordinates are relative to.
    Vec3 fit(const Vec3& centre, double extent, std::size_t staticTriangles);

    /// The base triangle of a static mesh: where it already is with the spatial order of serial `order`, or appended
    /// now (then `appended` is set and the caller writes it, its order included, at `baseVertex`, `baseTriangle`).
    struct Place {
        bool appended = false;
        std::uint32_t baseVertex = 0;
        std::uint32_t baseTriangle = 0;
    };
    Place place(StaticEntry& entry, std::size_t vertices, std::size_t triangles, std::uint64_t order = 0);

    std::size_t vertices() const { return m_vertices; }
    std::size_t triangles() const { return m_triangles; }

private:
    Vec3 m_origin = Vec3::Zero();
    std::uint64_t m_epoch = 0;  ///< bumped whenever the region is rebuilt (0: none yet)
    double m_extent = 0.0;      ///< extent of the cluster when the region's origin was chosen
    std::size_t m_vertices = 0;
    std::size_t m_triangles = 0;
};

}  // namespace cullide
