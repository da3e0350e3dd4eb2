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
    runTrial(a, 2001, 9.0, 2.0);
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

}  // namespace
}  // namespace cullide
