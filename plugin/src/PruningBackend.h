// The seam between the frame pipeline (GpuCuller, LevelPipelines) and what runs CULLIDE's image-space visibility
// test: the GL implementation (gl/VisibilityPass) and the CPU reference (ReferenceVisibility), which computes the
// same pixels in the same float arithmetic and is the oracle of the GL one. The level's loop over iterations
// (VisibilityLevel.h) drives either; a backend only answers "which items survive one iteration of this view".
#pragma once

#include "cullide/Stats.h"
#include "cullide/Types.h"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide {

/// Geometry of the frame's active cluster, uploaded once per cluster: positions and boxes relative to the upload
/// origin, in float (what the visibility test rasterises).
struct GpuGeometry {
    std::vector<float> positions;       ///< xyz per vertex
    std::vector<std::uint32_t> indices;  ///< 3 global vertex indices per triangle
    /// The first keptPositions floats of `positions` and keptIndices of `indices` are the same as in the previous
    /// upload (static geometry, and meshes that did not change: a deforming mesh's indices, a mesh at rest): what the
    /// device already holds of them is not sent again.
    std::size_t keptPositions = 0;
    std::size_t keptIndices = 0;
    std::vector<float> boxes;           ///< min xyz, max xyz per box (rounded outwards)
    double coordinateBound = 0.0;       ///< max |coordinate| over positions and boxes (for error bounds)
};

/// The items of one level. Item i belongs to owner[i] (a compact object id) and is drawn as the primitives
/// prims[primBegin[i] .. primBegin[i + 1]) (a triangle index, or a box index | CULLIDE_PRIM_BOX_BIT).
struct LevelItems {
    std::vector<std::uint32_t> owner;
    std::vector<std::uint32_t> primBegin{0};
    std::vector<std::uint32_t> prims;
    std::vector<Aabb> bounds;  ///< per item, relative to the upload origin, inflated by nothing
    std::size_t size() const { return owner.size(); }
    void clear() {
        owner.clear();
        primBegin.assign(1, 0);
        prims.clear();
        bounds.clear();
    }
};

/// The orthographic view box of one iteration and the float parameters every view of it uses (the shaders'
/// uniforms), per world axis. Made by fitView (VisibilityLevel.h).
struct View {
    Aabb box;  ///< relative to the upload origin
    float lo[3];          ///< box minimum
    float pixelScale[3];  ///< pixels per unit
    float depthScale[3];  ///< normalized depth per unit
    float halfSize[3];    ///< reliable mode: half side of the tested pixel square (half pixel + margin + slack)
    float depthPad[3];    ///< reliable mode: margin + slack added to depth ranges (normalized depth)
};

/// What one iteration leaves: the items still alive and what the next view is fitted to.
struct IterationResult {
    /// Compute back-end invocations whose footprint exceeded the loop bound: the iteration pruned nothing.
    std::uint32_t overflows = 0;
    std::uint32_t alive = 0;
    std::uint32_t ownerMin = 0;  ///< smallest and largest owner among the alive items (unset when none)
    std::uint32_t ownerMax = 0;
    Aabb bounds;  ///< of the alive items' boxes as uploaded (deviceBoundsOf, VisibilityLevel.h)
};

/// A backend failure in the middle of a frame (a GL error). The culler finishes that frame without pruning: every
/// triangle the CPU pre-pass keeps goes to the exact stage, so no contact is lost.
class BackendError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class PruningBackend {
public:
    virtual ~PruningBackend() = default;
    PruningBackend() = default;
    PruningBackend(const PruningBackend&) = delete;
    PruningBackend& operator=(const PruningBackend&) = delete;

    /// Takes the cluster's geometry; `geometry` must stay alive (unchanged) until the next upload.
    virtual void upload(const GpuGeometry& geometry, Stats& stats) = 0;
    /// Forgets what was uploaded (after a GL error): the next upload sends everything.
    virtual void forgetUploads() = 0;
    /// Bytes held on the device (0 for a CPU backend).
    virtual std::size_t deviceBytes() const = 0;
    /// GL_RENDERER and the device chosen (Stats::renderer, Stats::device).
    virtual std::string renderer() const = 0;
    virtual std::string device() const = 0;

    /// Starts a level: every item alive, the first iteration's view `view`. `items` stays alive (unchanged) until
    /// the level ends.
    virtual void beginLevel(const LevelItems& items, const View& view, LevelStats& level, Stats& stats) = 0;
    /// One iteration: both views along every enabled axis over the alive items; an item stays alive when it is not
    /// fully visible in any of them. Owner ids are packed into the low `idBits` bits of each pixel.
    virtual IterationResult iterate(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) = 0;
    /// The alive set now, 0/1 per item.
    virtual void readAlive(std::vector<std::uint8_t>& alive, LevelStats& level, Stats& stats) = 0;
};

}  // namespace cullide
