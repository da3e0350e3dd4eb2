// Far outliers (issue #13) on the reference backend: reliable mode exact at every magnitude the validation accepts,
// in both pipelines and at every resolution, and far objects costing what near ones cost.
#include "Compare.h"
#include "LevelPipelines.h"
#include "ReferenceLevelsSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace cullide::test {
namespace {


/// Far outliers (issue #13) on the reference backend, so that every resolution is affordable: two overlapping unit
/// cubes at the origin, a unit cube alone at (s, s, s), and an overlapping pair at -s as small as double coordinates
/// there allow. Reliable mode must give the exact answer at every magnitude the validation accepts (1e39 and 1e300:
/// beyond float range), in both pipelines, at every resolution; and the far objects must cost what near ones cost:
/// the lone outlier nothing (no partner: it takes part in no level), the far pair what the same pair costs at -10.
class FarOutliers : public ::testing::TestWithParam<std::pair<Pipeline, int>> {};

std::string farOutliersName(const ::testing::TestParamInfo<std::pair<Pipeline, int>>& param) {
    return std::string(param.param.first == Pipeline::Paper ? "Paper" : "Auto") + std::to_string(param.param.second);
}

std::vector<TriangleMesh> outlierScene(double s, double farPairAt) {
    const double h = std::max(1.0, s * 1e-12);  // the far pair's side: coordinates near s are spaced s * 2^-52
    const std::vector<std::pair<Vec3, double>> cubes = {{Vec3(0, 0, 0), 1.0}, {Vec3(0.5, 0.5, 0.5), 1.0},
                                                        {Vec3(s, s, s), 1.0}, {Vec3::Constant(farPairAt), h},
                                                        {Vec3::Constant(farPairAt + 0.5 * h), h}};
    std::vector<TriangleMesh> meshes;
    for (const auto& [corner, side] : cubes) {
        TriangleMesh m = cubesAt({Vec3::Zero()})[0];
        for (Vec3& v : m.vertices) v = corner + side * v;
        meshes.push_back(std::move(m));
    }
    return meshes;
}

/// Items entering and leaving every iteration of every level: what the levels cost, independent of the clock.
std::vector<std::size_t> levelWork(const Stats& stats) {
    std::vector<std::size_t> work;
    for (const LevelStats& level : stats.levels) work.insert(work.end(), level.itemsPerIteration.begin(), level.itemsPerIteration.end());
    return work;
}

TEST_P(FarOutliers, ReliableIsExactAndFarObjectsCostWhatNearOnesCost) {
    const auto [pipeline, resolution] = GetParam();
    auto culler = referenceLevelsCuller(referenceLevels(pipeline, Mode::Reliable, resolution));
    auto exact = createReferenceCuller(Settings{});
    const auto nearMeshes = outlierScene(3.0, -10.0);  // the lone cube near, the pair at -10
    Result nearResult;
    culler->run(asObjects(nearMeshes), nearResult);
    ASSERT_EQ(nearResult.stats.clusters, 2u);
    for (double s : {1e4, 1e8, 1e12, 1e13, 1e20, 1e30, 1e38, 1e39, 1e300}) {
        const auto meshes = outlierScene(s, -s);
        const auto objects = asObjects(meshes);
        Result truth, got;
        exact->run(objects, truth);
        culler->run(objects, got);
        const Comparison c = compare(truth, got);
        ASSERT_EQ(truth.pairs.size(), 2u) << "s=" << s << ": the near pair and the far pair";
        EXPECT_EQ(c.missed, 0u) << "s=" << s << ": " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << s;
        EXPECT_TRUE(c.objectPairsEqual) << s;
        EXPECT_EQ(got.stats.clusters, 2u) << s;
        EXPECT_EQ(got.stats.prepassObjectsOut, 4u) << s << ": the lone outlier takes part in nothing";
        // A cluster wider than kRasterisableExtent is not rasterised (its triangles go to the exact stage unpruned).
        const bool farPairRasterised = 1.5 * std::max(1.0, s * 1e-12) <= kRasterisableExtent;
        EXPECT_EQ(got.stats.unrasterisedClusters, farPairRasterised ? 0u : 1u) << "s=" << s;
        if (s <= 1e12) {  // the same unit cubes, exactly representable relative to their cluster's centre
            EXPECT_EQ(levelWork(got.stats), levelWork(nearResult.stats)) << s;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(EveryResolution, FarOutliers,
                         ::testing::Values(std::make_pair(Pipeline::Auto, 16), std::make_pair(Pipeline::Auto, 256),
                                           std::make_pair(Pipeline::Auto, 1024), std::make_pair(Pipeline::Paper, 16),
                                           std::make_pair(Pipeline::Paper, 64), std::make_pair(Pipeline::Paper, 256),
                                           std::make_pair(Pipeline::Paper, 512)),
                         farOutliersName);

}  // namespace
}  // namespace cullide::test
