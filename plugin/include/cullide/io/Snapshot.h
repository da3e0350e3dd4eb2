// Headless snapshots of a scene for figures and demos (the paper's Fig. 5(c-d): the objects with their potentially
// colliding triangles highlighted and their intersecting triangles marked). Rendered off screen with OpenGL on the
// same headless device selection as the culler; no window system is needed.
// Part of the cullide_io library (CMake: cullide::io; pkg-config: cullide-io), not of the culler.
#pragma once

#include "cullide/Types.h"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cullide {

/// An 8-bit RGBA image, rows top to bottom: pixel (x, y) starts at rgba[4 * (y * width + x)].
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgba;
};

/// One object of a snapshot. Colours are linear 0..1 components.
struct SnapshotItem {
    /// World space. Must not be null (render() throws std::invalid_argument naming the item). Triangles with an
    /// out-of-range index or a non-finite vertex are skipped; the rest of the mesh is drawn.
    const TriangleMesh* mesh = nullptr;
    std::array<float, 3> color{0.7f, 0.7f, 0.7f};
    /// Triangle indices drawn in the highlight colour (e.g. Result::pcsTriangles). Sorted order is customary but
    /// not required; indices past the mesh's triangle count are ignored. Null: nothing highlighted and nothing dimmed.
    const std::vector<std::uint32_t>* highlighted = nullptr;
    /// Triangle indices drawn in the mark colour (e.g. the intersecting triangles); a marked triangle is drawn
    /// marked even when it is also highlighted. Same conventions as `highlighted`.
    const std::vector<std::uint32_t>* marked = nullptr;
};

/// Camera and colours. The camera is orthographic, looks at the centre of `frame` and fits the whole frame box into
/// the image with a small margin. Y is up: the camera sits in direction (cos e sin a, sin e, cos e cos a) from the
/// centre for azimuth a and elevation e (azimuth 0 looks along -z, 90 along -x; elevation 90 looks straight down).
struct SnapshotView {
    int width = 640;   ///< 1 .. 8192
    int height = 480;  ///< 1 .. 8192
    double azimuthDeg = 35;
    double elevationDeg = 25;
    /// Region to fit (finite, not empty; may be flat). Default: the bounds of every drawable triangle.
    std::optional<Aabb> frame;
    std::array<float, 3> background{1.0f, 1.0f, 1.0f};
    std::array<float, 3> highlight{1.0f, 0.8f, 0.1f};
    std::array<float, 3> mark{0.85f, 0.1f, 0.1f};
    /// Draw the non-highlighted triangles of objects that have a `highlighted` list faded toward the background,
    /// as in the paper's figure (an object whose list is empty is faded entirely).
    bool dimUnhighlighted = true;
};

class SnapshotRenderer {
public:
    virtual ~SnapshotRenderer() = default;
    SnapshotRenderer() = default;
    SnapshotRenderer(const SnapshotRenderer&) = delete;
    SnapshotRenderer& operator=(const SnapshotRenderer&) = delete;

    /// A renderer with its own headless GL context, chosen like the culler's: `device` as Settings::device ("" =
    /// env CULLIDE_GL_DEVICE, else automatic; "hardware", "software", "surfaceless" or an index). Throws
    /// GlUnavailableError (cullide/Culler.h) without a usable GL device. Use it from one thread at a time.
    static std::unique_ptr<SnapshotRenderer> create(const std::string& device = "");

    /// Renders the items (flat Lambert shading, lit from both sides: meshes are open soups; thin darker triangle
    /// edges where triangles are large enough on screen). An empty scene gives the background. Throws
    /// std::invalid_argument for a null mesh, a size outside 1..8192, non-finite angles, colours outside [0, 1] or
    /// an empty or non-finite frame. The same input gives the same bytes.
    virtual Image render(const std::vector<SnapshotItem>& items, const SnapshotView& view) = 0;

    /// GL_RENDERER of the context (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)").
    virtual std::string renderer() const = 0;
};

}  // namespace cullide
