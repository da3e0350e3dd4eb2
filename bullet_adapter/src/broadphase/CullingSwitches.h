// The broadphase's culling switches (Culling per CulledKind) and what they mean in a step: which kinds may be
// culled at all, which are culled this step (On, or Culling::Auto's decision: AutoCulling), and the culler's budget
// during an Auto trial.
#pragma once

#include "broadphase/AutoCulling.h"
#include "broadphase/CullingPolicy.h"
#include "cullide_bullet/CullideBroadphase.h"

#include <array>
#include <string>

namespace cullide::bullet {

class CullingSwitches {
public:
    /// `device`: Settings::device, for the hardware-device test of Auto (hasHardwareGlDevice), made once, on first need.
    explicit CullingSwitches(std::string device) : m_device(std::move(device)) {}

    void set(CulledKind kind, Culling mode) { m_modes[index(kind)] = mode; }
    Culling get(CulledKind kind) const { return m_modes[index(kind)]; }
    void setAutoOnAnyDevice(bool enable) { m_autoAnyDevice = enable; }

    /// Kinds that may be culled in some step: On, or Auto where it trials.
    CulledKinds possible() const;
    /// Kinds culled in the step under way (after beginStep).
    const CulledKinds& culled() const { return m_culled; }
    /// Whether the kind is culled in the step under way: On, or Auto's decision (Off and, before the first step,
    /// Auto: false).
    bool isCulled(CulledKind kind) const {
        return m_modes[index(kind)] == Culling::On || (m_modes[index(kind)] == Culling::Auto && m_culled[kind]);
    }
    /// Whether some kind is On (its culler is made and run on the step's thread, as soon as it has pairs).
    bool anyOn() const;

    /// Starts a step: `pairs[k]` the step's candidate pairs of kind k; `cullerReady`: a culler exists;
    /// `measurable`: the step's cost can be measured (the dispatcher is a CullideCollisionDispatcher).
    void beginStep(const AutoCulling::Counts& pairs, bool cullerReady, bool measurable);
    /// How many of the kind's `pairs` this step's candidates are culled (the first ones in the pair cache's order): all
    /// of them but in an Auto trial's ramp.
    std::size_t pairsToCull(CulledKind kind, std::size_t pairs) const {
        return m_modes[index(kind)] == Culling::Auto ? m_auto.pairsToCull(index(kind), pairs) : pairs;
    }
    /// The culler's budget this step in ms (an Auto trial's culled step), 0: none.
    double cullerBudgetMs() const { return m_auto.cullerBudgetMs(); }
    /// The step begun last could not run the culler it planned (no culler of a large enough margin yet): it is no
    /// trial step.
    void cancelStep() { m_cancelled = true; }
    /// The step begun last cost `ms` (culling plus narrow phase); `abandoned`: its culler ran past its budget.
    void endStep(double ms, bool abandoned);
    /// Whether an Auto kind has pairs this step but no culler exists yet (the broadphase then starts making one).
    bool wantsCuller(const AutoCulling::Counts& pairs) const;

    CullingDecision decision(CulledKind kind) const;

private:
    static std::size_t index(CulledKind k) { return static_cast<std::size_t>(k); }
    /// Whether Auto trials here: a hardware GL device, or setAutoOnAnyDevice.
    bool autoTrials() const;
    std::array<bool, AutoCulling::kKinds> autoKinds() const;

    std::string m_device;
    std::array<Culling, AutoCulling::kKinds> m_modes{Culling::Auto, Culling::Auto, Culling::Auto, Culling::Auto};
    bool m_autoAnyDevice = false;
    mutable int m_hardware = -1;  ///< hasHardwareGlDevice, asked on first need (-1: not yet)
    AutoCulling m_auto;
    CulledKinds m_culled;
    bool m_measurable = false;
    bool m_cancelled = false;
};

}  // namespace cullide::bullet
