// The last stage of a frame: the result's pairs from the pre-pass's object pairs and the surviving triangles —
// mesh pairs with at least one triangle pair within the margin (the exact stage), pairs with a box proxy by a CPU
// box test. Pairs are a function of the input alone; the visibility levels only decide how much exact work is left.
#pragma once

#include "ExactStage.h"
#include "FrameState.h"
#include "cullide/Result.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <vector>

namespace cullide {

class PairAssembly {
public:
    /// Fills result.pairs (sorted as frame.pairs) and result.pcs from `frame` (read only).
    void run(const FrameState& frame, const Settings& settings, ExactStage& exact, Result& result);

private:
    /// The device exact stage's pairs (frame.devicePairs), sorted into m_device: m_deviceKeep[i] where the filter
    /// certified pair i, or its double boxes overlap and the exact predicate keeps it (every candidate without
    /// Settings::exactTriangles).
    void decideDevicePairs(const FrameState& frame, const Settings& settings, TaskPool& pool, Stats& stats);

    // Allocations kept between frames.
    std::vector<DevicePair> m_device;
    std::vector<std::uint8_t> m_deviceKeep;
    std::vector<ExactJobResult> m_jobResults;
    std::vector<std::uint8_t> m_touches;
};

}  // namespace cullide
