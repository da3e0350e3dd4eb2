// A PruningBackend that runs the GL backend and the CPU reference (ReferenceVisibility) side by side, iteration by
// iteration, and records every difference: the alive sets item by item and the counters the level loop reads (alive
// count, owner range, bounds). The GL backend's answer drives the culler, so a whole frame runs exactly as in
// production while every iteration of every level is checked.
#pragma once

#include "CullerBackends.h"
#include "PruningBackend.h"

#include <memory>
#include <string>
#include <vector>

namespace cullide::test {

struct LockstepLog {
    std::size_t levels = 0;
    std::size_t iterations = 0;
    std::size_t itemsIn = 0;      ///< items entering the compared iterations, summed
    std::size_t itemsPruned = 0;  ///< items the GL backend pruned in them, summed
    std::size_t mismatches = 0;   ///< iterations where the two differ in any way
    std::size_t itemsDiffering = 0;
    std::vector<std::string> details;  ///< the first few differences, for the failure message
    std::string summary() const;
};

/// A factory for createGpuCuller(settings, factory): each culler gets a lockstep backend writing into `log`, around a
/// GL backend made with `options`.
PruningBackendFactory lockstepFactory(std::shared_ptr<LockstepLog> log, GlBackendOptions options = {});

}  // namespace cullide::test
