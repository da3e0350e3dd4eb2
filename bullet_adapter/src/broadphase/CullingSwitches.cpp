#include "broadphase/CullingSwitches.h"

#include "cullide/Culler.h"

namespace cullide::bullet {

bool CullingSwitches::autoTrials() const {
    if (m_autoAnyDevice) return true;
    if (m_hardware < 0) m_hardware = hasHardwareGlDevice(m_device) ? 1 : 0;
    return m_hardware == 1;
}

std::array<bool, AutoCulling::kKinds> CullingSwitches::autoKinds() const {
    std::array<bool, AutoCulling::kKinds> kinds{};
    bool any = false;
    for (std::size_t k = 0; k < kinds.size(); ++k) any = any || m_modes[k] == Culling::Auto;
    if (!any || !autoTrials()) return kinds;  // the device is asked once, and only while some switch is Auto
    for (std::size_t k = 0; k < kinds.size(); ++k) kinds[k] = m_modes[k] == Culling::Auto;
    return kinds;
}

CulledKinds CullingSwitches::possible() const {
    CulledKinds kinds;
    const auto autoKind = autoKinds();
    for (std::size_t k = 0; k < kinds.on.size(); ++k) kinds.on[k] = m_modes[k] == Culling::On || autoKind[k];
    return kinds;
}

bool CullingSwitches::anyOn() const {
    for (const Culling m : m_modes)
        if (m == Culling::On) return true;
    return false;
}

void CullingSwitches::beginStep(const AutoCulling::Counts& pairs, bool cullerReady, bool measurable) {
    m_measurable = measurable;
    m_cancelled = false;
    auto autoKind = autoKinds();
    if (!measurable) autoKind = {};  // nothing to time the steps with: Auto does not cull
    m_auto.beginStep(autoKind, pairs, cullerReady);
    for (std::size_t k = 0; k < m_culled.on.size(); ++k)
        m_culled.on[k] = m_modes[k] == Culling::On || (autoKind[k] && m_auto.culled(k));
}

void CullingSwitches::endStep(double ms, bool abandoned) {
    if (m_cancelled) {
        m_auto.cancelStep();
        return;
    }
    m_auto.endStep(ms, abandoned);
}

bool CullingSwitches::wantsCuller(const AutoCulling::Counts& pairs) const {
    const auto autoKind = autoKinds();
    for (std::size_t k = 0; k < pairs.size(); ++k)
        if (autoKind[k] && pairs[k] > 0) return m_measurable;
    return false;
}

CullingDecision CullingSwitches::decision(CulledKind kind) const {
    const std::size_t k = index(kind);
    CullingDecision d;
    d.culled = m_culled.on[k];
    d.abandonedTrials = m_auto.abandonedTrials();
    if (m_modes[k] != Culling::Auto) {
        d.state = m_modes[k] == Culling::On ? "culled" : "not culled";
        return d;
    }
    if (!autoTrials()) {
        d.state = "not trialled";
        return d;
    }
    d.state = m_auto.state(k);
    if (d.state.empty()) d.state = "waiting";
    d.unculledMs = m_auto.unculledMs(k);
    d.culledMs = m_auto.culledMs(k);
    return d;
}

}  // namespace cullide::bullet
