// The GPU culler on shared meshes placed by transforms: exactly the reference's pairs, with and without GPU levels,
// both pipelines; static keys with transforms refresh when the transform changes.
#include "Compare.h"
#include "GlTestSupport.h"
#include "Instances.h"

#include <gtest/gtest.h>

#include <set>

namespace cullide::test {
namespace {

Settings withLevels(GpuLevels levels, Pipeline pipeline) {
    Settings s;
    s.resolution = 64;
    s.gpuLevels = levels;
    s.pipeline = pipeline;
    s.exactThreshold = 0;
    return s;
}

struct Case {
    GpuLevels levels;
    Pipeline pipeline;
};

class TransformedInstances : public ::testing::TestWithParam<Case> {};

TEST_P(TransformedInstances, MatchTheReferenceAndTheWorldSpaceTwins) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, withLevels(GetParam().levels, GetParam().pipeline));
    auto reference = createReferenceCuller(Settings{});
    std::size_t total = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        const InstanceScene scene = randomInstances(seed, 24, seed == 2, 4);
        Result expected, got, twins;
        reference->run(scene.worldObjects(), expected);
        culler->run(scene.instances(), got);
        culler->run(scene.worldObjects(), twins);
        const Comparison cmp = compare(expected, got);
        EXPECT_EQ(cmp.missed, 0u) << "seed " << seed << ": " << cmp.firstMissed;
        EXPECT_EQ(cmp.spurious, 0u) << "seed " << seed;
        EXPECT_TRUE(cmp.objectPairsEqual) << "seed " << seed;
        EXPECT_EQ(trianglePairs(got), trianglePairs(twins)) << "seed " << seed;
        total += cmp.expected;
    }
    EXPECT_GT(total, 40u) << "scenes too sparse to test anything";
}

INSTANTIATE_TEST_SUITE_P(Pipelines, TransformedInstances,
                         ::testing::Values(Case{GpuLevels::Never, Pipeline::Auto},
                                           Case{GpuLevels::Always, Pipeline::Auto},
                                           Case{GpuLevels::Always, Pipeline::Paper}));

// A static key whose transform changes (same version) must not reuse the boxes of the old placement.
TEST(TransformedInstances, StaticKeyFollowsTheTransform) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, withLevels(GpuLevels::Never, Pipeline::Auto));
    auto reference = createReferenceCuller(Settings{});
    InstanceScene scene = randomInstances(5, 12, false);
    std::size_t pairs = 0, changes = 0;
    std::set<FlatPair> last;
    for (int frame = 0; frame < 6; ++frame) {
        std::vector<Object> objects = scene.instances();
        for (std::size_t i = 0; i < objects.size(); ++i) objects[i].staticKey = i + 1;  // version stays 0
        Result expected, got;
        reference->run(objects, expected);
        culler->run(objects, got);
        EXPECT_EQ(trianglePairs(got), trianglePairs(expected)) << "frame " << frame;
        pairs += trianglePairs(expected).size();
        changes += trianglePairs(expected) != last ? 1 : 0;
        last = trianglePairs(expected);
        // Every other instance moves on (same key, same version): its placement, not its mesh, changed.
        for (std::size_t i = 0; i < scene.transforms.size(); i += 2)
            scene.transforms[i].translation += Vec3(0.12, -0.07, 0.05);
    }
    EXPECT_GT(pairs, 30u);
    EXPECT_GE(changes, 4u) << "the moves must change the pairs";
}

}  // namespace
}  // namespace cullide::test
