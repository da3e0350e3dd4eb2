// The GPU culler's reliable mode misses nothing on random soups, at every resolution, in both pipelines.
#include "Compare.h"
#include "GlTestSupport.h"
#include "ReliableSettings.h"

#include <gtest/gtest.h>

namespace cullide::test {
namespace {

struct SweepCase {
    Pipeline pipeline;
    int resolution;
};

class ReliableSweep : public ::testing::TestWithParam<SweepCase> {};

TEST_P(ReliableSweep, MissesNothingOnRandomSoups) {
    const SweepCase c = GetParam();
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(c.resolution, c.pipeline));
    auto reference = createReferenceCuller(Settings{});
    std::size_t expectedTotal = 0;
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
        const auto meshes = randomSoups(seed, 16, 80, 0.2);
        const auto objects = asObjects(meshes);
        Result expected, got;
        reference->run(objects, expected);
        culler->run(objects, got);
        const Comparison cmp = compare(expected, got);
        EXPECT_EQ(cmp.missed, 0u) << "seed " << seed << " res " << c.resolution << ": " << cmp.firstMissed;
        EXPECT_EQ(cmp.spurious, 0u) << "seed " << seed;
        EXPECT_TRUE(cmp.objectPairsEqual) << "seed " << seed;
        expectedTotal += cmp.expected;
    }
    EXPECT_GT(expectedTotal, 20u) << "scenes too sparse to test anything";
}

INSTANTIATE_TEST_SUITE_P(Resolutions, ReliableSweep,
                         ::testing::Values(SweepCase{Pipeline::Auto, 16}, SweepCase{Pipeline::Auto, 64},
                                           SweepCase{Pipeline::Auto, 256}, SweepCase{Pipeline::Auto, 1024},
                                           SweepCase{Pipeline::Paper, 16}, SweepCase{Pipeline::Paper, 256}));

}  // namespace
}  // namespace cullide::test
