// Culling::Auto: whether the pairs of a kind go through the culler this step, decided by timing the steps of the
// running scene with the kind culled against without. Pure bookkeeping (no clock, no Bullet): the broadphase tells it
// which kinds have pairs and what each step cost, and asks which kinds to cull, how many of a kind's pairs, and under
// what budget.
//
// The trial of one kind, while the other kinds keep their state. A step's cost is the broadphase's culling plus the
// dispatcher's narrow phase.
// 1. Baseline: a step with the kind not culled; its cost is b.
// 2. Ramp: steps that cull a growing share of the kind's pairs (the first eighth of them in the pair cache's order,
//    then half, then all). After each, its extra cost over b is extrapolated to all of the kind's pairs (linearly in
//    the share): where that is no saving, culling cannot pay and the kind is not culled; otherwise the next share
//    runs, and costs less than b. The first share's step is bounded by its culler's budget, so no trial step costs
//    more than about twice a step without the trial plus 1 ms.
// 3. The step that culls all of them decides: the kind is culled from then on if it cost less than b.
// Only one kind is in a trial at a time. A culled step's culler gets a budget (b + 1 ms) and abandons its frame
// past it (Culler::run with a budget; the step's culled pairs then run Bullet's algorithms): the trial has lost.
// The decision holds until the kind's pair count leaves [half, twice] the count it was measured at, and at least
// kMinStepsBetweenTrials steps; a trial that repeats the decision before it with one side at least kClearLoss times
// the other doubles that hold (up to kMaxStepsBetweenTrials), as the culler's own GpuLevels::Auto does.
#pragma once

#include <array>
#include <cstddef>
#include <string>

namespace cullide::bullet {

class AutoCulling {
public:
    /// The culling switches (CullideBroadphase's CulledKind order).
    static constexpr std::size_t kKinds = 4;
    using Counts = std::array<std::size_t, kKinds>;

    /// Starts a step. `autoKinds[k]`: kind k's switch is Auto and may be trialled; `pairs[k]`: kind k's pairs this
    /// step (0: none); `cullerReady`: a culler can run this step.
    void beginStep(const std::array<bool, kKinds>& autoKinds, const Counts& pairs, bool cullerReady);
    /// Whether kind k is culled this step (its decision, or a culled step of its trial).
    bool culled(std::size_t k) const { return m_culled[k]; }
    /// How many of kind k's pairs (the first ones in the pair cache's order) are culled this step: all of them but
    /// in a trial's ramp.
    std::size_t pairsToCull(std::size_t k, std::size_t pairs) const;
    /// The culler's budget this step in ms (a trial's culled step), or 0: none.
    double cullerBudgetMs() const { return m_budgetMs; }
    /// The step begun last cost `ms` (culling plus narrow phase); `abandoned`: the culler gave up its frame.
    void endStep(double ms, bool abandoned);
    /// The step begun last did not run as planned (its culler was not there): it counts for nothing, and a trial it
    /// belonged to starts over.
    void cancelStep();

    /// "measuring", "on", "off", or "" before any trial.
    std::string state(std::size_t k) const;
    /// The last completed trial of kind k: its baseline step, and its step culling all of the kind's pairs or, where
    /// the ramp stopped early, that step's cost extrapolated to all of them (0 before a trial completes).
    double unculledMs(std::size_t k) const { return m_kinds[k].offMs; }
    double culledMs(std::size_t k) const { return m_kinds[k].onMs; }
    /// Trial steps whose culler ran past its budget.
    std::size_t abandonedTrials() const { return m_abandoned; }

    static constexpr int kMinStepsBetweenTrials = 120;
    static constexpr int kMaxStepsBetweenTrials = 120 * 32;
    static constexpr double kClearLoss = 2.0;
    static constexpr double kBudgetSlackMs = 1.0;
    /// The ramp's shares of the kind's pairs.
    static constexpr std::array<double, 3> kShares{0.125, 0.5, 1.0};

private:
    struct Kind {
        bool decided = false;
        bool on = false;
        int stepsDecided = 0;
        int holdSteps = kMinStepsBetweenTrials;
        std::size_t pairsMeasured = 0;
        double offMs = 0.0, onMs = 0.0;  ///< the last completed trial's steps
    };
    struct Trial {
        bool active = false;
        std::size_t kind = 0;
        int stage = -1;           ///< -1: the baseline step; else the index into kShares of the next culled step
        double baselineMs = 0.0;
    };

    bool wantsTrial(std::size_t k, std::size_t pairs) const;
    /// Ends the trial with the kind culled (from then on) or not, `onMs` the culled cost measured or extrapolated.
    void decide(double onMs);

    std::array<Kind, kKinds> m_kinds;
    std::array<bool, kKinds> m_culled{};
    Trial m_trial;
    bool m_stepIsTrial = false;  ///< the step begun last is a step of m_trial
    double m_budgetMs = 0.0;
    std::size_t m_abandoned = 0;
};

}  // namespace cullide::bullet
