// AutoLevels: GpuLevels::Auto decided by timing both paths on the scene (issue #13, item 4).
#include "AutoLevels.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide {
namespace {

using Path = AutoLevels::Path;

/// Runs the four trial frames of a scene of `triangles` triangles with the given timed costs (warm-ups cost 1000 ms,
/// which must not count) and returns the paths chosen.
std::vector<Path> runTrial(AutoLevels& a, std::size_t triangles, double cpuMs, double gpuMs) {
    std::vector<Path> paths;
    for (int frame = 0; frame < 4; ++frame) {
        const Path p = a.choose(triangles);
        EXPECT_TRUE(a.measuring());
        EXPECT_EQ(a.decision(), "measuring");
        paths.push_back(p);
        a.record(p, frame < 2 ? 1000.0 : (p == Path::Cpu ? cpuMs : gpuMs));
    }
    return paths;
}

TEST(AutoLevels, AlternatesBothPathsThenRunsTheFasterMeasured) {
    AutoLevels slowGpu;
    EXPECT_EQ(runTrial(slowGpu, 1000, 2.0, 9.0), (std::vector<Path>{Path::Cpu, Path::Gpu, Path::Cpu, Path::Gpu}));
    EXPECT_FALSE(slowGpu.measuring());
    EXPECT_EQ(slowGpu.decision(), "cpu");
    EXPECT_EQ(slowGpu.cpuMs(), 2.0);
    EXPECT_EQ(slowGpu.gpuMs(), 9.0);
    for (int frame = 0; frame < 10; ++frame) EXPECT_EQ(slowGpu.choose(1000), Path::Cpu);

    AutoLevels fastGpu;
    runTrial(fastGpu, 1000, 9.0, 2.0);
    EXPECT_EQ(fastGpu.decision(), "gpu");
    for (int frame = 0; frame < 10; ++frame) {
        EXPECT_EQ(fastGpu.choose(1000), Path::Gpu);
        fastGpu.record(Path::Gpu, 50.0);  // frames after the trial do not change the decision
    }
    EXPECT_EQ(fastGpu.gpuMs(), 2.0);
}

TEST(AutoLevels, MeasuresAgainWhenTheSceneHalvesOrDoubles) {
    AutoLevels a;
    runTrial(a, 1000, 2.0, 9.0);
    EXPECT_EQ(a.choose(2000), Path::Cpu);  // within [half, twice]: the decision holds
    EXPECT_EQ(a.choose(500), Path::Cpu);
    EXPECT_FALSE(a.measuring());
    // Doubled, but too soon after the trial: the decision holds (a colliding set that keeps changing size must not
    // pay for trials every few frames).
    for (int frame = 2; frame < 120; ++frame) EXPECT_EQ(a.choose(frame % 2 == 0 ? 5000 : 1000), Path::Cpu) << frame;
    EXPECT_FALSE(a.measuring());
    // Doubled and more, 120 frames on: a new trial, and this time the GPU wins.
    runTrial(a, 2001, 4.0, 2.0);  // (a CPU path that loses by more than 2x + 1 ms would not be trialled again)
    EXPECT_EQ(a.decision(), "gpu");
    for (int frame = 0; frame < 120; ++frame) EXPECT_EQ(a.choose(2001), Path::Gpu);
    // Less than half: measured again.
    runTrial(a, 1000, 2.0, 9.0);
    EXPECT_EQ(a.decision(), "cpu");
}

TEST(AutoLevels, EmptyFramesAndSizeJumpsDuringATrial) {
    AutoLevels a;
    EXPECT_EQ(a.choose(0), Path::Cpu);  // an empty probe frame is no trial frame
    a.record(Path::Cpu, 0.1);
    EXPECT_EQ(a.choose(0), Path::Cpu);
    a.record(Path::Cpu, 0.1);
    // The trial starts with the first frame that has triangles: CPU, GPU, ...
    EXPECT_EQ(a.choose(10), Path::Cpu);
    a.record(Path::Cpu, 0.1);
    EXPECT_EQ(a.choose(10), Path::Gpu);
    a.record(Path::Gpu, 0.1);
    // The scene jumps from 10 to 5000 triangles mid-trial: the trial starts over at its new size.
    runTrial(a, 5000, 9.0, 2.0);
    EXPECT_EQ(a.decision(), "gpu");
    EXPECT_EQ(a.gpuMs(), 2.0);
}

TEST(AutoLevels, AFrameOnTheOtherPathIsNotATrialFrame) {
    AutoLevels a;
    const Path first = a.choose(100);
    ASSERT_EQ(first, Path::Cpu);
    a.record(Path::Gpu, 1.0);  // not what was chosen: ignored
    EXPECT_EQ(a.choose(100), Path::Cpu);
    a.record(Path::Cpu, 1.0);
    EXPECT_EQ(a.choose(100), Path::Gpu);
}

/// Runs frames of a scene whose size alternates between 1000 and 5000 triangles every frame, from a decided state,
/// until one starts a new trial (at most `limit` frames); returns how many frames ran before it and sets `size` to
/// that frame's size. The starting frame is left unrecorded: runTrial's first frame starts the trial over.
int framesUntilNextTrial(AutoLevels& a, int limit, std::size_t& size) {
    for (int frame = 0; frame < limit; ++frame) {
        size = frame % 2 == 0 ? 5000 : 1000;
        a.choose(size);
        if (a.measuring()) return frame;
    }
    return limit;
}

TEST(AutoLevels, AClearLoserIsRetriedLessOftenEachTimeItLosesAgain) {
    AutoLevels a;
    runTrial(a, 1000, 2.0, 9.0);  // the GPU loses by 4.5x
    EXPECT_EQ(a.holdFrames(), 120);
    // Each trial after a size change costs two GPU frames; each one that the GPU loses clearly again doubles the
    // hold before the next, up to 3,840 frames.
    for (int hold : {240, 480, 960, 1920, 3840, 3840}) {
        std::size_t size = 0;
        const int waited = framesUntilNextTrial(a, 10000, size);
        EXPECT_GE(waited, a.holdFrames());
        EXPECT_LE(waited, a.holdFrames() + 1);
        runTrial(a, size, 2.0, 9.0);
        EXPECT_EQ(a.decision(), "cpu");
        EXPECT_EQ(a.holdFrames(), hold);
    }
}

TEST(AutoLevels, ACloseOrChangedDecisionSetsTheShortHoldBack) {
    AutoLevels a;
    std::size_t size = 0;
    // The trial starts on the first size change once the hold is over: that frame or the next.
    auto waitHold = [&](int hold) {
        const int waited = framesUntilNextTrial(a, 1000, size);
        EXPECT_TRUE(waited == hold || waited == hold + 1) << waited << " frames for a hold of " << hold;
    };
    runTrial(a, 1000, 2.0, 9.0);
    waitHold(120);
    runTrial(a, size, 2.0, 9.0);
    EXPECT_EQ(a.holdFrames(), 240);
    waitHold(240);
    runTrial(a, size, 2.0, 3.0);  // the same winner, but by less than twice: back to the short hold
    EXPECT_EQ(a.decision(), "cpu");
    EXPECT_EQ(a.holdFrames(), 120);
    waitHold(120);
    runTrial(a, size, 2.0, 9.0);  // clear again, the same winner: doubled
    EXPECT_EQ(a.holdFrames(), 240);
    waitHold(240);
    runTrial(a, size, 9.0, 2.0);  // the GPU wins now, clearly: a new decision starts at the short hold
    EXPECT_EQ(a.decision(), "gpu");
    EXPECT_EQ(a.holdFrames(), 120);
}

TEST(AutoLevels, AGpuTrialFrameGetsTheLastCpuFramePlusSlack) {
    AutoLevels a;
    EXPECT_EQ(a.choose(100), Path::Cpu);
    EXPECT_EQ(a.trialBudgetMs(), 0.0);  // a CPU trial frame has no budget
    a.record(Path::Cpu, 3.0);
    EXPECT_EQ(a.choose(100), Path::Gpu);
    EXPECT_DOUBLE_EQ(a.trialBudgetMs(), 4.0);
    a.record(Path::Gpu, 50.0);  // the GPU's warm-up
    EXPECT_EQ(a.choose(100), Path::Cpu);
    a.record(Path::Cpu, 2.0);
    EXPECT_EQ(a.choose(100), Path::Gpu);
    EXPECT_DOUBLE_EQ(a.trialBudgetMs(), 3.0);
    // Abandoned past its budget and finished on the CPU path: its time, recorded as the GPU's, makes the CPU win.
    a.record(Path::Gpu, 5.0);
    EXPECT_EQ(a.decision(), "cpu");
    EXPECT_EQ(a.choose(100), Path::Cpu);
    EXPECT_EQ(a.trialBudgetMs(), 0.0);  // no trial frame
}

TEST(AutoLevels, NoCpuTrialFrameWhereItWouldStallTheLoop) {
    AutoLevels far;
    runTrial(far, 1000, 9.0, 2.0);  // the GPU wins by more than 2x + 1 ms
    for (int frame = 0; frame < 120; ++frame) EXPECT_EQ(far.choose(1000), Path::Gpu);
    // Twice the size after the hold: a trial would run a CPU frame of ~18 ms against GPU frames of ~4: skipped.
    EXPECT_EQ(far.choose(2001), Path::Gpu);
    EXPECT_FALSE(far.measuring());
    EXPECT_EQ(far.holdFrames(), 240);  // held twice as long instead

    AutoLevels near;
    runTrial(near, 1000, 3.0, 2.0);  // the GPU wins, but a CPU frame would cost less than 2x + 1 ms
    for (int frame = 0; frame < 120; ++frame) EXPECT_EQ(near.choose(1000), Path::Gpu);
    EXPECT_EQ(near.choose(2001), Path::Cpu);  // a new trial, starting on the CPU path
    EXPECT_TRUE(near.measuring());
}

}  // namespace
}  // namespace cullide
