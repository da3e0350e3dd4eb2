#include "AutoLevels.h"

#include <algorithm>

namespace cullide {

AutoLevels::Path AutoLevels::choose(std::size_t triangles) {
    m_pending = false;
    if (triangles == 0) return Path::Cpu;  // nothing for the levels: no trial frame, no decision needed
    const bool resized = triangles > 2 * m_triangles || 2 * triangles < m_triangles;
    // A new trial: the first, a size jump during one, or a size change once the decision has held long enough
    // (a scene whose colliding set keeps changing size would otherwise pay for the slower path every few frames).
    if (m_step == 0 || (resized && (measuring() || m_framesDecided >= m_holdFrames))) {
        const double scale = m_triangles > 0 ? double(triangles) / double(m_triangles) : 1.0;
        if (m_decided && !measuring() && m_decision == Path::Gpu &&
            m_cpuMs * scale > 2.0 * m_gpuMs * scale + kBudgetSlackMs) {
            // The CPU path lost by more than a frame loop can absorb: no CPU trial frame, a longer hold.
            m_holdFrames = std::min(2 * m_holdFrames, kMaxFramesBetweenTrials);
            m_framesDecided = 0;
            m_triangles = triangles;
        } else {
            m_step = 0;
            m_triangles = triangles;
        }
    }
    if (!measuring()) {
        ++m_framesDecided;
        return m_decision;
    }
    m_pending = true;
    return trialPath(m_step);
}

void AutoLevels::record(Path path, double ms) {
    if (!m_pending || path != trialPath(m_step)) return;
    m_pending = false;
    if (path == Path::Cpu) m_lastCpuFrameMs = ms;
    if (m_step >= 2) (path == Path::Cpu ? m_trialCpuMs : m_trialGpuMs) = ms;  // steps 0, 1: warm-ups
    if (++m_step < kTrialFrames) return;
    m_cpuMs = m_trialCpuMs;
    m_gpuMs = m_trialGpuMs;
    const Path decision = m_gpuMs < m_cpuMs ? Path::Gpu : Path::Cpu;
    const bool clear = std::max(m_cpuMs, m_gpuMs) >= kClearLoss * std::min(m_cpuMs, m_gpuMs);
    m_holdFrames = m_decided && decision == m_decision && clear
                       ? std::min(2 * m_holdFrames, kMaxFramesBetweenTrials)
                       : kMinFramesBetweenTrials;
    m_decision = decision;
    m_decided = true;
    m_framesDecided = 0;
}

double AutoLevels::trialBudgetMs() const {
    if (!m_pending || trialPath(m_step) != Path::Gpu || m_lastCpuFrameMs <= 0.0) return 0.0;
    return m_lastCpuFrameMs + kBudgetSlackMs;
}

std::string AutoLevels::decision() const {
    if (measuring()) return "measuring";
    return m_decision == Path::Gpu ? "gpu" : "cpu";
}

}  // namespace cullide
