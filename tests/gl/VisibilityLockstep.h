// A PruningBackend that runs the GL backend and the CPU reference (ReferenceVisibility) side by side, level by level,
// and records every difference: iteration by iteration the view (fitted on the device after the first) and what the
// iteration left (alive count, owner range, bounds), then the level's alive set item by item. The GL backend's answer
// drives the culler, so a whole frame runs exactly as in production while every iteration of every level is checked.
#pragma once

#include "CullerBackends.h"
#include "PruningBackend.h"
#include "cullide/Settings.h"
#include "cullide/Types.h"

#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace cullide::test {

struct LockstepLog {
    std::size_t levels = 0;
    std::size_t iterations = 0;
    std::size_t itemsIn = 0;      ///< items entering the compared iterations, summed
    std::size_t itemsPruned = 0;  ///< items the GL backend pruned in them, summed
    std::size_t levelsDeferred = 0;  ///< levels whose read-back waited for the frame's collect()
    std::size_t levelsAhead = 0;  ///< of the levels, run ahead (their survivors compared through the next level's)
    std::size_t uploads = 0;         ///< geometry uploads, each checked: the device's positions bit for bit
    std::size_t mappedVertices = 0;  ///< of their vertices, mapped on the device (MappedMesh), summed
    std::size_t builtBoxes = 0;      ///< of their boxes, built on the device (GpuGeometry::builtRanges), summed
    std::size_t exactPairs = 0;      ///< pairs the device exact stage wrote (compared with the reference's), summed
    std::size_t exactCertified = 0;  ///< of those, certified intersecting by its filter
    std::size_t mismatches = 0;   ///< differences found (an iteration's view or result, a level's survivors, an
                                  ///< upload's positions or boxes)
    std::size_t itemsDiffering = 0;
    std::vector<std::string> details;  ///< the first few differences, for the failure message
    std::string summary() const;
};

/// A factory for createGpuCuller(settings, factory): each culler gets a lockstep backend writing into `log`, around a
/// GL backend made with `options`.
PruningBackendFactory lockstepFactory(std::shared_ptr<LockstepLog> log, GlBackendOptions options = {});

/// One configuration checked in lockstep.
struct LockstepCase {
    Pipeline pipeline;
    Mode mode;
    Backend backend;
    int resolution;
    unsigned axes = 7;  ///< Settings::axes
    double margin = 0.0;  ///< Settings::margin
};

/// The case as a test-name part, e.g. "PaperReliableCompute64" ("...Margin" with a margin).
std::string lockstepName(const LockstepCase& c);
void PrintTo(const LockstepCase& c, std::ostream* os);

/// Settings of the case that run every level (GpuLevels::Always, exactThreshold 0) on two threads; Pipeline::Paper
/// cases iterate until the set stops changing (minPruneFraction 0).
Settings lockstepSettings(const LockstepCase& c);

/// Runs `frames` through a culler whose GL backend is checked against the reference; returns the comparison. The
/// caller has already made sure a GL device is there (CULLIDE_GPU_CULLER_OR_SKIP).
LockstepLog runInLockstep(const Settings& settings, const std::vector<std::vector<TriangleMesh>>& frames);

}  // namespace cullide::test
