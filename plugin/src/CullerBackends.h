// Internal: the GPU culler with the pruning backend of the caller's choice. Production uses the GL backend; tests
// plug in the CPU reference (unit tests without GL, pruning-strength tests) or a recorder around the GL backend that
// checks it against the reference iteration by iteration.
#pragma once

#include "PruningBackend.h"
#include "cullide/Culler.h"

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

namespace cullide {

/// Makes the backend for a culler's settings; may throw GlUnavailableError (no usable GL device).
using PruningBackendFactory = std::function<std::unique_ptr<PruningBackend>(const Settings&)>;

/// Knobs of the GL backend that only tests turn.
struct GlBackendOptions {
    /// The compute back-end's bands as on a hardware GPU (about CULLIDE_TARGET_INVOCATIONS records per build) on a
    /// software renderer too, which otherwise scans 4,096 pixels per band: so that llvmpipe runs the GPU's records.
    bool shortBands = false;
    /// Added to every read-back's wait (and counted in LevelStats::waitMs like it): a device whose round trips are
    /// slow, so that tests can check how the level's CPU time is split between its set-up and its waits.
    double readBackDelayMs = 0.0;
    /// Where set: after every upload, every position the device holds (the mapped meshes' as map.comp wrote them) is
    /// read back into it, so that tests can hold them to allPositions bit for bit: a read-back that no stat counts.
    std::shared_ptr<std::vector<float>> positionsAfterUpload;
    /// Where set: after every upload, the boxes the device holds (GpuGeometry::boxes, of which only what changed is
    /// sent) are read back into it likewise.
    std::shared_ptr<std::vector<float>> boxesAfterUpload;
    /// Where above 0: work groups along x per dispatch at most, below the device's own limit
    /// (GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]), so that tests reach the split dispatches and rows of work groups that
    /// only scenes of millions of records or vertices need otherwise.
    std::size_t maxWorkGroups = 0;
    /// Where above 0: the exact pairs the device's buffer holds at first (it grows after a frame that needed more),
    /// so that tests reach an overflow.
    std::size_t exactCapacity = 0;
};

/// The GL visibility test (gl/VisibilityPass). Throws GlUnavailableError without a usable GL device.
std::unique_ptr<PruningBackend> createGlPruningBackend(const Settings& settings, const GlBackendOptions& options = {});

/// The CPU reference of the visibility test (ReferenceVisibility.h): no GL, single-threaded, exact same answers.
std::unique_ptr<PruningBackend> createReferencePruningBackend(const Settings& settings);

/// createGpuCuller with `makeBackend` in place of the GL backend: the same frame pipeline, the same fallback rules
/// (GpuLevels::Never calls no factory; a GlUnavailableError from the factory means the CPU path, unless GPU levels
/// were demanded).
std::unique_ptr<Culler> createGpuCuller(const Settings& settings, const PruningBackendFactory& makeBackend);

}  // namespace cullide
