// Settings::exactTriangles = false (the Bullet adapter's setting), with and without GPU levels: the surviving
// candidate pairs, a superset of the exact pairs, and no exact test run.
#include "Compare.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>

namespace cullide::test {
namespace {

TEST(ExactTriangles, OffGivesTheCandidatesASupersetWithoutExactTests) {
    // Settings::exactTriangles = false (the Bullet adapter's setting): the surviving candidate pairs, a superset
    // of the exact pairs, and no exact test run; object pairs may be more (candidates without an exact pair).
    for (GpuLevels levels : {GpuLevels::Never, GpuLevels::Always}) {
        Settings settings;
        settings.gpuLevels = levels;
        settings.exactThreshold = 0;
        settings.exactTriangles = false;
        settings.margin = 0.01;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
        const auto meshes = randomSoups(21, 40, 100, 0.08);
        const auto objects = asObjects(meshes);
        Result reference, candidates;
        createReferenceCuller(settings)->run(objects, reference);
        culler->run(objects, candidates);
        const Comparison c = compare(reference, candidates);
        ASSERT_GT(c.expected, 0u);
        EXPECT_EQ(c.missed, 0u) << c.firstMissed;
        EXPECT_GT(c.spurious, 0u) << "candidates should include pairs whose boxes overlap but triangles do not";
        EXPECT_EQ(candidates.stats.exactTests, 0u);
        EXPECT_EQ(candidates.stats.intersectingTrianglePairs, 0u);
        std::size_t listed = 0;
        for (const ObjectPair& p : candidates.pairs) listed += p.triangles.size();
        EXPECT_EQ(listed, candidates.stats.candidateTrianglePairs);
    }
}


}  // namespace
}  // namespace cullide::test
