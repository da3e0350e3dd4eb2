// Culler::run with a budget (cullide/Culler.h): a frame past its budget is abandoned (no pairs, Stats::abandoned)
// and the culler stays usable; within it, or without one, the frame is the reference's. The CPU path (no GL).
#include "cullide/Culler.h"
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide {
namespace {

std::vector<Object> asObjects(const std::vector<TriangleMesh>& meshes) {
    std::vector<Object> objects(meshes.size());
    for (std::size_t i = 0; i < meshes.size(); ++i) objects[i].mesh = &meshes[i];
    return objects;
}

std::vector<ObjectIndexPair> allPairs(std::size_t n) {
    std::vector<ObjectIndexPair> pairs;
    for (std::uint32_t a = 0; a < n; ++a)
        for (std::uint32_t b = a + 1; b < n; ++b) pairs.emplace_back(a, b);
    return pairs;
}

std::size_t trianglePairs(const Result& r) {
    std::size_t n = 0;
    for (const ObjectPair& p : r.pairs) n += p.triangles.size();
    return n;
}

TEST(CullerBudget, AFramePastItsBudgetIsAbandonedAndTheCullerStaysUsable) {
    scenes::RandomSceneOptions options;
    options.objects = 30;
    options.maxTriangles = 400;
    const std::vector<TriangleMesh> meshes = scenes::makeRandomScene(21, options);
    const std::vector<Object> objects = asObjects(meshes);
    const std::vector<ObjectIndexPair> pairs = allPairs(objects.size());
    Settings settings;
    settings.gpuLevels = GpuLevels::Never;
    const auto culler = createGpuCuller(settings);
    Result reference;
    createReferenceCuller(settings)->run(objects, pairs, reference);
    ASSERT_GT(trianglePairs(reference), 0u);

    Result r;
    culler->run(objects, pairs, r, 1e-6);  // spent before the first stage ends
    EXPECT_TRUE(r.stats.abandoned);
    EXPECT_TRUE(r.pairs.empty());
    EXPECT_TRUE(r.pcs.empty());

    culler->run(objects, pairs, r, 60000.0);  // a budget it keeps
    EXPECT_FALSE(r.stats.abandoned);
    EXPECT_EQ(trianglePairs(r), trianglePairs(reference));
    culler->run(objects, pairs, r, 0.0);  // no budget
    EXPECT_FALSE(r.stats.abandoned);
    EXPECT_EQ(trianglePairs(r), trianglePairs(reference));
}

TEST(CullerBudget, TheReferenceCullersIgnoreIt) {
    scenes::RandomSceneOptions options;
    options.objects = 8;
    const std::vector<TriangleMesh> meshes = scenes::makeRandomScene(5, options);
    const std::vector<Object> objects = asObjects(meshes);
    Result r;
    createReferenceCuller(Settings{})->run(objects, allPairs(objects.size()), r, 1e-6);
    EXPECT_FALSE(r.stats.abandoned);
}

}  // namespace
}  // namespace cullide
