#include "RunRecord.h"

#include <algorithm>
#include <cmath>

namespace cullide::bench {

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void RunRecord::add(const FrameOutput& out, const PairSet* exact) {
    m_total.push_back(out.totalMs);
    m_faults.push_back(out.minorFaults);
    for (const StageTime& s : out.stages) {
        if (!m_stages.count(s.name)) m_stageOrder.push_back(s.name);
        m_stages[s.name].push_back(s.ms);
    }
    m_trianglesKnown = m_trianglesKnown && out.trianglePairsKnown;
    m_reportedTriangles += out.pairs.triangles().size();
    m_reportedObjects += out.pairs.objects().size();
    if (out.candidates) {
        m_hasCandidates = true;
        m_candidates += *out.candidates;
    }
    m_contacts += out.contacts;
    m_maxUploaded = std::max(m_maxUploaded, out.bytesUploaded);
    m_maxReadBack = std::max(m_maxReadBack, out.bytesReadBack);
    m_maxDevice = std::max(m_maxDevice, out.gpuDeviceBytes);
    m_sumUploaded += out.bytesUploaded;
    m_draws.push_back(static_cast<double>(out.draws));
    m_readBacks.push_back(static_cast<double>(out.blockingReadBacks));
    if (out.gpuTimerMs) m_gpuTimerMs.push_back(*out.gpuTimerMs);
    if (out.pool)
        for (int i = 0; i < 3; ++i) m_pool[i].push_back(static_cast<double>((*out.pool)[static_cast<std::size_t>(i)]));
    if (!out.levels.is_null()) m_lastLevels = out.levels;
    if (exact != nullptr) {
        m_compared = true;
        m_triangles += compareTriangles(exact->triangles(), out.pairs.triangles());
        m_objects += compareObjects(exact->objects(), out.pairs.objects());
    }
}

void RunRecord::write(nlohmann::json& r) const {
    r["frames"] = m_total.size();
    if (!m_total.empty()) {
        r["ms"] = {{"median", median(m_total)},
                   {"min", *std::min_element(m_total.begin(), m_total.end())},
                   {"max", *std::max_element(m_total.begin(), m_total.end())}};
    }
    nlohmann::json stages = nlohmann::json::array();
    for (const std::string& name : m_stageOrder) stages.push_back({name, median(m_stages.at(name))});
    r["stages"] = stages;  // [[name, median ms], ...] in pipeline order
    r["reported_object_pairs"] = m_reportedObjects;
    r["reported_triangle_pairs"] = m_trianglesKnown ? nlohmann::json(m_reportedTriangles) : nlohmann::json();
    r["contacts"] = m_contacts;
    if (m_compared) {
        r["exact_object_pairs"] = m_objects.expected;
        r["exact_triangle_pairs"] = m_triangles.expected;
        r["missed_object_pairs"] = m_objects.missed;
        r["extra_object_pairs"] = m_objects.extra;
        if (m_trianglesKnown) {
            r["missed_triangle_pairs"] = m_triangles.missed;
            r["extra_triangle_pairs"] = m_triangles.extra;
        }
    }
    if (m_hasCandidates) {
        r["candidate_triangle_pairs"] = m_candidates;
        if (m_compared && m_triangles.expected > 0)
            r["false_positive_ratio"] = static_cast<double>(m_candidates) / static_cast<double>(m_triangles.expected);
    }
    r["bytes_uploaded_max"] = m_maxUploaded;
    r["gpu_device_bytes_max"] = m_maxDevice;
    r["bytes_uploaded_mean"] = m_total.empty() ? 0.0 : static_cast<double>(m_sumUploaded) / static_cast<double>(m_total.size());
    r["bytes_read_back_max"] = m_maxReadBack;
    r["draws_median"] = median(m_draws);
    r["blocking_read_backs_median"] = median(m_readBacks);
    r["draws_max"] = m_draws.empty() ? 0.0 : *std::max_element(m_draws.begin(), m_draws.end());
    r["blocking_read_backs_max"] = m_readBacks.empty() ? 0.0 : *std::max_element(m_readBacks.begin(), m_readBacks.end());
    std::vector<double> faults(m_faults.begin(), m_faults.end());
    r["minor_faults_median"] = median(faults);  // per frame or step: memory freshly touched (see frame_minor_faults)
    if (!m_pool[0].empty()) {
        // Per frame: the culler's parallel loops and the wake-ups they waited for (Stats::poolCalls and the rest).
        // Means: a sleep a few frames in ten would vanish in a median.
        auto mean = [](const std::vector<double>& v) {
            double sum = 0.0;
            for (double x : v) sum += x;
            return sum / static_cast<double>(v.size());
        };
        r["pool_calls_mean"] = mean(m_pool[0]);
        r["pool_worker_wakes_mean"] = mean(m_pool[1]);
        r["pool_caller_sleeps_mean"] = mean(m_pool[2]);
    }
    // GPU timer: only when every timed frame had a valid one (a median of some frames would read as all).
    if (!m_gpuTimerMs.empty() && m_gpuTimerMs.size() == m_total.size()) r["gpu_timer_ms_median"] = median(m_gpuTimerMs);
    if (!m_lastLevels.is_null() && !m_lastLevels.empty()) r["levels_last_frame"] = m_lastLevels;
}

void RunRecord::writeFrames(nlohmann::json& r) const {
    auto rounded = [](const std::vector<double>& ms) {
        nlohmann::json a = nlohmann::json::array();
        for (double v : ms) a.push_back(std::round(v * 1000.0) / 1000.0);  // microseconds: enough, and short
        return a;
    };
    r["frame_ms"] = rounded(m_total);
    nlohmann::json stages = nlohmann::json::object();
    for (const std::string& name : m_stageOrder) stages[name] = rounded(m_stages.at(name));
    r["stage_frame_ms"] = stages;
    r["frame_minor_faults"] = m_faults;
}

}  // namespace cullide::bench
