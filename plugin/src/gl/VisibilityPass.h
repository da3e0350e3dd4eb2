// The image-space visibility test of CULLIDE on the GPU: one level (objects, groups or triangles), iterated over
// the three axes (both view directions each) until its set stops changing.
#pragma once

#include "cullide/Settings.h"
#include "cullide/Stats.h"
#include "cullide/Types.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace cullide::gl {

class EglContext;

/// Geometry uploaded once per frame: positions and boxes relative to `origin` (float on the GPU).
struct GpuGeometry {
    std::vector<float> positions;       ///< xyz per vertex
    std::vector<std::uint32_t> indices;  ///< 3 global vertex indices per triangle
    /// The first keptPositions floats of `positions` and keptIndices of `indices` are the same as in the previous
    /// upload (static geometry): what the device already holds of them is not sent again.
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

class VisibilityPass {
public:
    VisibilityPass(EglContext& context, const Settings& settings);
    ~VisibilityPass();
    VisibilityPass(const VisibilityPass&) = delete;
    VisibilityPass& operator=(const VisibilityPass&) = delete;

    /// Uploads the frame's geometry; `geometry` must stay alive (unchanged) until the next upload.
    void upload(const GpuGeometry& geometry, Stats& stats);
    /// Forgets what the device holds (after a GL error): the next upload sends everything.
    void forgetUploads();
    /// Bytes held on the device: buffer capacities plus the view images.
    std::size_t deviceBytes() const;

    /// Prunes the items: survivors[i] is true when item i may intersect an item of another owner. Runs at most
    /// `maxIterations` iterations (each: three axes, both directions) and stops when the set stops changing.
    void prune(const LevelItems& items, std::vector<std::uint8_t>& survivors, LevelStats& level, Stats& stats);

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::gl
