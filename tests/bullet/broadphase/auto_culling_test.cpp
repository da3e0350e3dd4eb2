// Culling::Auto's trial as pure bookkeeping (bullet_adapter/src/broadphase/AutoCulling.h): the baseline step, the
// ramp of culled shares with its early stop, the decision, the budget, abandoned and cancelled steps, the hold.
#include "broadphase/AutoCulling.h"

#include <gtest/gtest.h>

namespace cullide::test {
namespace {

using bullet::AutoCulling;

constexpr std::size_t kPair = 0;  // CulledKind::GImpactPair
const std::array<bool, AutoCulling::kKinds> kAutoPair{true, false, false, false};
const AutoCulling::Counts kPairs{80, 0, 0, 0};

/// One step of a trial: begins it, checks what it culls, ends it with cost `ms`.
void step(AutoCulling& a, double ms, bool expectCulled, std::size_t expectPairs, bool abandoned = false) {
    a.beginStep(kAutoPair, kPairs, true);
    EXPECT_EQ(a.culled(kPair), expectCulled);
    EXPECT_EQ(a.pairsToCull(kPair, kPairs[kPair]), expectPairs);
    a.endStep(ms, abandoned);
}

TEST(AutoCulling, RampsThroughSharesAndCullsWhereTheFullStepPays) {
    AutoCulling a;
    EXPECT_EQ(a.state(kPair), "");
    step(a, 10.0, false, 80);  // baseline
    EXPECT_EQ(a.state(kPair), "measuring");
    a.beginStep(kAutoPair, kPairs, true);
    EXPECT_DOUBLE_EQ(a.cullerBudgetMs(), 10.0 + AutoCulling::kBudgetSlackMs);
    EXPECT_EQ(a.pairsToCull(kPair, 80), 10u);  // an eighth
    a.endStep(9.5, false);                     // 0.5 saved on an eighth: 4 on all, extrapolated
    step(a, 8.0, true, 40);                    // half
    step(a, 6.0, true, 80);                    // all: decides
    EXPECT_EQ(a.state(kPair), "on");
    EXPECT_DOUBLE_EQ(a.unculledMs(kPair), 10.0);
    EXPECT_DOUBLE_EQ(a.culledMs(kPair), 6.0);
    a.beginStep(kAutoPair, kPairs, true);
    EXPECT_TRUE(a.culled(kPair));
    EXPECT_EQ(a.pairsToCull(kPair, 80), 80u);
    EXPECT_DOUBLE_EQ(a.cullerBudgetMs(), 0.0);  // no trial: no budget
}

TEST(AutoCulling, StopsAtTheFirstShareWhoseExtrapolationCannotPay) {
    AutoCulling a;
    step(a, 2.0, false, 80);
    step(a, 2.5, true, 10);  // +0.5 on an eighth: +4 on all
    EXPECT_EQ(a.state(kPair), "off");
    EXPECT_DOUBLE_EQ(a.culledMs(kPair), 6.0);
    a.beginStep(kAutoPair, kPairs, true);
    EXPECT_FALSE(a.culled(kPair));
}

TEST(AutoCulling, AnAbandonedCullerLoses) {
    AutoCulling a;
    step(a, 3.0, false, 80);
    step(a, 7.0, true, 10, true);
    EXPECT_EQ(a.state(kPair), "off");
    EXPECT_EQ(a.abandonedTrials(), 1u);
}

TEST(AutoCulling, ACancelledStepStartsTheTrialOver) {
    AutoCulling a;
    step(a, 3.0, false, 80);
    a.beginStep(kAutoPair, kPairs, true);
    a.cancelStep();
    step(a, 3.0, false, 80);  // the baseline again
    EXPECT_EQ(a.state(kPair), "measuring");
}

TEST(AutoCulling, NothingWithoutAutoPairsOrCuller) {
    AutoCulling a;
    a.beginStep(kAutoPair, kPairs, false);  // no culler yet
    EXPECT_FALSE(a.culled(kPair));
    a.endStep(1.0, false);
    a.beginStep({false, false, false, false}, kPairs, true);
    EXPECT_FALSE(a.culled(kPair));
    a.endStep(1.0, false);
    a.beginStep(kAutoPair, {0, 0, 0, 0}, true);
    EXPECT_FALSE(a.culled(kPair));
    a.endStep(1.0, false);
    EXPECT_EQ(a.state(kPair), "");
}

TEST(AutoCulling, HoldsUntilThePairCountChangesAndDoublesTheHoldOnAClearRepeat) {
    AutoCulling a;
    step(a, 2.0, false, 80);
    step(a, 10.0, true, 10);  // clear loss
    ASSERT_EQ(a.state(kPair), "off");
    const AutoCulling::Counts doubled{200, 0, 0, 0};
    for (int s = 0; s < AutoCulling::kMinStepsBetweenTrials; ++s) {  // the hold: no trial, even at twice the pairs
        a.beginStep(kAutoPair, doubled, true);
        EXPECT_FALSE(a.culled(kPair)) << s;
        a.endStep(2.0, false);
        EXPECT_EQ(a.state(kPair), "off") << s;
    }
    a.beginStep(kAutoPair, kPairs, true);  // held long enough, but the same size: no trial
    a.endStep(2.0, false);
    EXPECT_EQ(a.state(kPair), "off");
    a.beginStep(kAutoPair, doubled, true);  // twice the pairs: a new trial (its baseline)
    a.endStep(2.0, false);
    EXPECT_EQ(a.state(kPair), "measuring");
    a.beginStep(kAutoPair, doubled, true);
    EXPECT_TRUE(a.culled(kPair));
    a.endStep(10.0, false);  // the same clear loss: the hold doubles
    ASSERT_EQ(a.state(kPair), "off");
    for (int s = 0; s < 2 * AutoCulling::kMinStepsBetweenTrials; ++s) {
        a.beginStep(kAutoPair, kPairs, true);  // half the pairs again
        a.endStep(2.0, false);
        EXPECT_EQ(a.state(kPair), "off") << s;
    }
    a.beginStep(kAutoPair, kPairs, true);
    a.endStep(2.0, false);
    EXPECT_EQ(a.state(kPair), "measuring");
}

}  // namespace
}  // namespace cullide::test
