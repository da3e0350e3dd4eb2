// Spatial orders of whole meshes, kept between frames: the order the visibility levels group triangles in, and
// the order the exact stage's box trees take their leaves in (a refit instead of a sort). An order only affects
// speed, never a result, so a kept order may be stale: it is recomputed now and then. What is kept from an order
// between frames (a moving mesh's own-frame group boxes) follows its serial (FrameState::orderSerial).
#pragma once

#include "FrameState.h"
#include "cullide/Object.h"
#include "cullide/TaskPool.h"

#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace cullide {

/// Every triangle of `mesh` (indices in range) in Morton order of its centroid over the centroids' bounds, ties in
/// index order: a permutation of [0, triangles). With `pool`, on its workers (the same order for any number).
void spatialOrder(const TriangleMesh& mesh, std::vector<std::uint32_t>& order, TaskPool* pool = nullptr);

class TriangleOrders {
public:
    /// A mesh without Object::staticKey may have moved or deformed: its order is recomputed after this many frames
    /// (rigid motion keeps an order good; deformation wears it down slowly).
    static constexpr std::uint64_t kRefreshFrames = 16;
    /// Orders unused for this many frames are dropped.
    static constexpr std::uint64_t kKeepFrames = 240;
    /// Meshes with fewer triangles are ordered one per worker; larger ones one after another on every worker.
    static constexpr std::size_t kSpreadTriangles = 16384;

    /// Starts a frame (call once per frame, before assign): drops orders unused for kKeepFrames frames and clears
    /// frame.order (one null entry per object).
    void beginFrame(std::size_t objectCount, FrameState& frame);

    /// Sets frame.order[o] for each active mesh o with wanted(o) to its kept order, computed now when it is missing
    /// or due; other entries are left as they are (assign may run more than once a frame, for different meshes).
    /// Orders are kept by the caller's mesh, objects[o].mesh (instances of one mesh share one order; a transformed
    /// object's order is that of its mesh, which the transform does not change), and recomputed when its vertex or
    /// triangle count changes, or its version for the staticKey it was computed for; kRefreshFrames after it was
    /// computed for an unkeyed mesh, or for an instance with another key (instances with keys of their own share it
    /// as unkeyed ones do). frame.orderSerial[o] tells one permutation from another (a computation that gives the
    /// same one keeps its serial): what is derived from an order holds while its serial does.
    /// Returns how many orders it computed.
    std::size_t assign(const std::vector<Object>& objects, FrameState& frame,
                       const std::function<bool(std::uint32_t)>& wanted, TaskPool& pool);

    std::size_t size() const { return m_entries.size(); }
    /// Orders computed since the culler was made (a stale order costs speed only: this says how often they are).
    std::uint64_t computed() const { return m_computed; }

private:
    struct Entry {
        std::size_t vertices = 0;
        std::size_t triangles = 0;
        std::uint64_t staticKey = 0;
        std::uint64_t version = 0;
        std::uint64_t dueFrame = 0;  ///< recomputed at this frame (meshes without staticKey)
        std::uint64_t serial = 0;    ///< which permutation `order` is: a new one whenever a computation changes it
        std::uint64_t lastFrame = 0;
        bool ready = false;
        std::vector<std::uint32_t> order;
    };
    bool current(const Entry& e, const Object& object) const;

    std::unordered_map<const TriangleMesh*, Entry> m_entries;
    std::uint64_t m_frame = 0;
    std::uint64_t m_computed = 0;
    std::uint64_t m_serial = 0;
};

}  // namespace cullide
