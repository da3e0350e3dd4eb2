// One object of a culling frame.
#pragma once

#include "cullide/Types.h"

#include <cstdint>

namespace cullide {

/// An object handed to the culler for one frame. Either a triangle soup in world space (mesh != nullptr) or a
/// box-only proxy (mesh == nullptr, box used). The culler does not keep the pointer beyond Culler::run().
struct Object {
    const TriangleMesh* mesh = nullptr;
    /// Box-only proxy (used when mesh == nullptr). Must be finite.
    Aabb box;
    /// Non-zero: a caller-chosen identity for geometry that does not change between frames (static geometry).
    /// The culler keeps such geometry on the GPU and re-uploads it only when (staticKey, version, counts) differ.
    std::uint64_t staticKey = 0;
    std::uint64_t version = 0;
};

}  // namespace cullide
