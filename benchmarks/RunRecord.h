// Accumulates per-frame outputs of one (scene, engine) run into the JSON record of results.json.
#pragma once

#include "Engine.h"
#include "PairSet.h"

#include <nlohmann/json.hpp>

#include <map>
#include <string>
#include <vector>

namespace cullide::bench {

class RunRecord {
public:
    /// Adds a timed frame; `exact` (may be null) is the exact answer of that frame.
    void add(const FrameOutput& out, const PairSet* exact);
    /// Fills ms, stages, pair counts, errors, costs and bytes into `record`.
    void write(nlohmann::json& record) const;
    /// Adds each timed frame's ms, stage ms and minor page faults ("frame_ms", "stage_frame_ms": {stage: [ms, ...]},
    /// "frame_minor_faults"), in frame order: which frames were slow and where (GpuLevels::Auto's trial frames are the
    /// ones with "gpu levels" > 0).
    void writeFrames(nlohmann::json& record) const;
    std::size_t frames() const { return m_total.size(); }

private:
    std::vector<double> m_total;
    std::vector<long> m_faults;
    std::vector<std::string> m_stageOrder;
    std::map<std::string, std::vector<double>> m_stages;
    Comparison m_triangles, m_objects;
    bool m_compared = false;
    bool m_trianglesKnown = true;
    std::size_t m_reportedTriangles = 0, m_reportedObjects = 0;
    std::size_t m_candidates = 0;
    bool m_hasCandidates = false;
    std::size_t m_contacts = 0;
    std::size_t m_maxUploaded = 0, m_maxReadBack = 0, m_sumUploaded = 0, m_maxDevice = 0;
    std::vector<double> m_draws, m_readBacks, m_gpuTimerMs;
    /// Per frame where the engine reports them: pool calls, worker wake-ups, caller sleeps.
    std::vector<double> m_pool[3];
    nlohmann::json m_lastLevels;  ///< the last timed frame's GPU levels
};

double median(std::vector<double> v);

}  // namespace cullide::bench
