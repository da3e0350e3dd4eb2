// The GPU culler against the brute-force reference: reliable mode misses nothing at any resolution.
#include "Compare.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cullide::test {
namespace {

Settings reliable(int resolution, Pipeline pipeline = Pipeline::Auto) {
    Settings s;
    s.resolution = resolution;
    s.pipeline = pipeline;
    s.exactThreshold = 0;  // always run every GPU level in tests
    return s;
}

TEST(GpuCuller, TwoCrossingTriangles) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, reliable(64));
    std::vector<TriangleMesh> meshes(2);
    meshes[0].vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    meshes[0].triangles = {{0, 1, 2}};
    meshes[1].vertices = {{0.2, 0.2, -0.5}, {0.2, 0.2, 0.5}, {0.9, 0.9, 0.0}};
    meshes[1].triangles = {{0, 1, 2}};
    Result r;
    culler->run(asObjects(meshes), r);
    ASSERT_EQ(r.pairs.size(), 1u);
    EXPECT_EQ(r.pairs[0].triangles.size(), 1u);
    EXPECT_EQ(r.pcs, (std::vector<std::uint32_t>{0, 1}));
    EXPECT_FALSE(r.stats.renderer.empty());
}

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
