// The two-line swap's figures: docs/swap.md, rendered from swap results files (one per machine class), each holding
// the machine and one or more runs of cullide-swap-bench with the culling switches each run was given and the rows
// its --json wrote. Every number on the page comes from those files.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace cullide::bench {

/// One run of cullide-swap-bench: the switches it was given (its flags, and NAME=VALUE for an environment switch;
/// empty for the defaults) and the file its --json wrote.
struct SwapRun {
    std::string switches;
    std::string jsonPath;
};

/// {"machine": ..., "runs": [{"switches": "...", "rows": [...]}, ...]}. `machine` is a machine description
/// (scripts/bench.sh's machine.json) or a results.json that holds one under "machine". Throws std::runtime_error on
/// unreadable or malformed input (a run file that is not an array of rows with a scene name).
nlohmann::json combineSwapRuns(const nlohmann::json& machine, const std::vector<SwapRun>& runs);

/// What a run's rows add up to (the page's summary line, the README's headline).
struct SwapSummary {
    std::size_t scenes = 0;
    double ratioMedian = 0.0, ratioMin = 0.0, ratioMax = 0.0;  ///< the swap's step over the faster Bullet world's
    std::string fastestScene, slowestScene;                     ///< where ratioMin and ratioMax were measured
    std::size_t lost = 0, contactPairSteps = 0;                 ///< object pairs with points lost, of those with points
    std::size_t pointsMissing = 0, points = 0;                  ///< contact keys missing, of the points compared
    std::size_t pointsExtra = 0;                                ///< contact keys the swap has and Bullet does not
    double deepestDiffMax = 0.0;                                ///< largest deepest-point difference of any scene
};
SwapSummary summarizeSwapRun(const nlohmann::json& run);

/// The setters a run's switches stand for ("the default switches" when none).
std::string swapSwitchesLabel(const std::string& switches);

/// Writes docs/swap.md from combined results (combineSwapRuns), at most one per machine class. Throws
/// std::runtime_error on I/O errors or malformed input.
void writeSwapPage(const std::vector<nlohmann::json>& results, const std::string& docPath);

}  // namespace cullide::bench
