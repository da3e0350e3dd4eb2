// The README's table of headline figures, generated from the same results files as docs/benchmarks.md (the culler
// against its fastest peer on the paper's environments) and docs/swap.md (the two-line swap against Bullet's
// pipelines), one column per machine class, so that no figure in the README is typed by hand.
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace cullide::bench {

/// The table (Markdown). `benchResults`: results.json documents (docs/bench/results-<class>.json); `swapResults`:
/// combined swap results (docs/bench/swap-<class>.json). Either may be empty; a figure without its record reads "–".
std::string headlineTable(const std::vector<nlohmann::json>& benchResults,
                          const std::vector<nlohmann::json>& swapResults);

/// Replaces the lines between the line holding "<!-- NAME:begin" and the line holding "<!-- NAME:end -->" in the file
/// at `path` with `text` (the marker lines stay). Throws std::runtime_error when the file cannot be read or written or
/// the markers are missing or out of order: the file is then left as it was.
void replaceMarkedBlock(const std::string& path, const std::string& name, const std::string& text);

}  // namespace cullide::bench
