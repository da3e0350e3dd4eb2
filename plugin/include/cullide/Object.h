// One object of a culling frame.
#pragma once

#include "cullide/Types.h"

#include <cstdint>

namespace cullide {

/// An object handed to the culler for one frame. Either a triangle soup in world space (mesh != nullptr) or a
/// box-only proxy (mesh == nullptr, box used). The culler does not keep the pointer beyond Culler::run().
struct Object {
    const TriangleMesh* mesh = nullptr;
    /// Optional (meshes only): the mesh is in its own frame and this maps it to world space, vertex by vertex as
    /// transformPoint() rounds it. Many objects can share one mesh, each with its own transform: the culler builds
    /// world-space vertices only for objects whose world box (the box of the transformed corners of the mesh box,
    /// exact for transformPoint's rounding) comes within the margin of another object, so far-apart instances cost
    /// a box each. nullptr: the mesh is already in world space. An object is rejected when its transform is not
    /// finite or maps the mesh box beyond the double range. Ignored for box-only proxies (their box is in world
    /// space). When GPU levels run, the mesh's own vertices stay on the device (sent again only when they change;
    /// found by the mesh's address and vertex count, then compared) and each frame sends only the transform.
    const Transform* transform = nullptr;
    /// Box-only proxy (used when mesh == nullptr). Must be finite.
    Aabb box;
    /// Non-zero: a caller-chosen identity for a mesh that does not change between frames, with `version` changed by
    /// the caller whenever its vertices or triangles do: changing the mesh without changing `version` is an error
    /// (stale boxes can miss contacts). The culler keeps what it derives from such a mesh between frames:
    /// - while (staticKey, version, vertex count, triangle count, transform) stay the same (static geometry): its
    ///   validation, its triangle boxes and its box tree (about 80 bytes per triangle). When GPU levels run, the mesh
    ///   is sent to the device once and kept there while the scene stays around the same place (see
    ///   docs/architecture.md).
    /// - with a transform that changes (a rigid body in motion): what holds in the mesh's own frame, its validation
    ///   and, when GPU levels run the Auto pipeline, its groups' boxes there (a few bytes per triangle). A mesh with a
    ///   transform counts as static geometry (and costs as much) from the second frame in a row with the same
    ///   transform: a body at rest keeps all of its boxes.
    /// Everything is recomputed when key, version or counts change, or when the mesh comes with a transform where it
    /// came without one (or the other way round). Entries unused for 240 frames are dropped. A key used by two
    /// objects of one frame is cached for the first only.
    std::uint64_t staticKey = 0;
    std::uint64_t version = 0;
};

}  // namespace cullide
