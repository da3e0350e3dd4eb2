#include "broadphase/AutoCulling.h"

#include <algorithm>
#include <cmath>

namespace cullide::bullet {

bool AutoCulling::wantsTrial(std::size_t k, std::size_t pairs) const {
    const Kind& kind = m_kinds[k];
    if (!kind.decided) return true;
    const bool resized = pairs > 2 * kind.pairsMeasured || 2 * pairs < kind.pairsMeasured;
    return resized && kind.stepsDecided >= kind.holdSteps;
}

void AutoCulling::beginStep(const std::array<bool, kKinds>& autoKinds, const Counts& pairs, bool cullerReady) {
    m_stepIsTrial = false;
    m_budgetMs = 0.0;
    // A trial whose kind lost its pairs, its Auto switch or the culler is dropped; it starts over later.
    if (m_trial.active && (!autoKinds[m_trial.kind] || pairs[m_trial.kind] == 0 || !cullerReady))
        m_trial.active = false;
    if (!m_trial.active && cullerReady) {
        for (std::size_t k = 0; k < kKinds; ++k) {
            if (!autoKinds[k] || pairs[k] == 0 || !wantsTrial(k, pairs[k])) continue;
            m_trial = Trial{true, k, -1, 0.0};
            m_kinds[k].pairsMeasured = pairs[k];
            break;
        }
    }
    for (std::size_t k = 0; k < kKinds; ++k) {
        Kind& kind = m_kinds[k];
        if (kind.decided && !(m_trial.active && m_trial.kind == k)) ++kind.stepsDecided;
        m_culled[k] = autoKinds[k] && cullerReady && kind.decided && kind.on;
    }
    if (m_trial.active) {
        m_stepIsTrial = true;
        const bool culledStep = m_trial.stage >= 0;
        m_culled[m_trial.kind] = culledStep;
        if (culledStep) m_budgetMs = m_trial.baselineMs + kBudgetSlackMs;
    }
}

std::size_t AutoCulling::pairsToCull(std::size_t k, std::size_t pairs) const {
    if (!m_trial.active || m_trial.kind != k || m_trial.stage < 0) return pairs;
    const double share = kShares[static_cast<std::size_t>(m_trial.stage)];
    return std::min(pairs, static_cast<std::size_t>(std::ceil(share * double(pairs))));
}

void AutoCulling::endStep(double ms, bool abandoned) {
    if (!m_stepIsTrial || !m_trial.active) return;
    m_stepIsTrial = false;
    const double b = m_trial.baselineMs;
    if (m_trial.stage < 0) {
        m_trial.baselineMs = ms;
        m_trial.stage = 0;
        return;
    }
    const double share = kShares[static_cast<std::size_t>(m_trial.stage)];
    if (abandoned) {  // the culler alone took more than the step without culling: it cannot pay
        ++m_abandoned;
        decide(std::max(ms, b + kBudgetSlackMs) / share);
        return;
    }
    if (m_trial.stage + 1 == static_cast<int>(kShares.size())) {  // all of the kind's pairs: measured
        decide(ms);
        return;
    }
    // The extra cost over the baseline grows with the share: extrapolated to all of the kind's pairs, it must be a
    // saving for the next share to run (which then costs less than the baseline: no stall).
    const double allPairs = b + (ms - b) / share;
    if (allPairs >= b) {
        decide(allPairs);  // cannot pay
        return;
    }
    ++m_trial.stage;
}

void AutoCulling::cancelStep() {
    if (m_stepIsTrial) m_trial.active = false;
    m_stepIsTrial = false;
}

void AutoCulling::decide(double onMs) {
    Kind& kind = m_kinds[m_trial.kind];
    const double offMs = m_trial.baselineMs;
    kind.offMs = offMs;
    kind.onMs = onMs;
    const bool on = onMs < offMs;
    const bool clear = std::max(onMs, offMs) >= kClearLoss * std::min(onMs, offMs);
    kind.holdSteps = kind.decided && on == kind.on && clear ? std::min(2 * kind.holdSteps, kMaxStepsBetweenTrials)
                                                            : kMinStepsBetweenTrials;
    kind.on = on;
    kind.decided = true;
    kind.stepsDecided = 0;
    m_trial.active = false;
}

std::string AutoCulling::state(std::size_t k) const {
    if (m_trial.active && m_trial.kind == k) return "measuring";
    if (!m_kinds[k].decided) return "";
    return m_kinds[k].on ? "on" : "off";
}

}  // namespace cullide::bullet
