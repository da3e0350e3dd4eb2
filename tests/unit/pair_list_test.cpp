// Culler::run over a list of object pairs (the Bullet adapter's object level hands the culler only the pairs whose
// triangles it reads): a listed pair is reported exactly as in a full run, an unlisted one never, and a malformed
// list is refused before anything runs. Both cullers, no GL (GpuLevels::Never).
#include "Compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <vector>

namespace cullide::test {
namespace {

std::vector<std::unique_ptr<Culler>> cullers() {
    Settings s;
    s.gpuLevels = GpuLevels::Never;
    s.margin = 0.01;
    std::vector<std::unique_ptr<Culler>> out;
    out.push_back(createGpuCuller(s));
    out.push_back(createReferenceCuller(s));
    return out;
}

TEST(PairList, ListedPairsAsInAFullRunOthersNever) {
    const auto meshes = randomSoups(17, 14, 60, 0.25);
    const auto objects = asObjects(meshes);
    for (const auto& culler : cullers()) {
        Result full;
        culler->run(objects, full);
        ASSERT_GT(full.pairs.size(), 4u) << "scene too sparse to test anything";
        // Every second pair of the full run, and pairs that do not overlap at all (they must stay absent).
        std::vector<ObjectIndexPair> only;
        std::vector<ObjectPair> expected;
        for (std::size_t i = 0; i < full.pairs.size(); i += 2) {
            only.emplace_back(full.pairs[i].a, full.pairs[i].b);
            expected.push_back(full.pairs[i]);
        }
        for (std::uint32_t a = 0; a < objects.size(); ++a)
            for (std::uint32_t b = a + 1; b < objects.size(); ++b) only.emplace_back(a, b);
        std::sort(only.begin(), only.end());
        only.erase(std::unique(only.begin(), only.end()), only.end());
        // Now every pair is listed: the full answer. Then only every second one.
        Result all;
        culler->run(objects, only, all);
        EXPECT_EQ(trianglePairs(all), trianglePairs(full));
        only.clear();
        for (const ObjectPair& p : expected) only.emplace_back(p.a, p.b);
        Result part;
        culler->run(objects, only, part);
        ASSERT_EQ(part.pairs.size(), expected.size());
        for (std::size_t i = 0; i < expected.size(); ++i) {
            EXPECT_EQ(part.pairs[i].a, expected[i].a);
            EXPECT_EQ(part.pairs[i].b, expected[i].b);
            EXPECT_EQ(part.pairs[i].triangles.size(), expected[i].triangles.size());
        }
        Result none;
        culler->run(objects, std::vector<ObjectIndexPair>{}, none);
        EXPECT_TRUE(none.pairs.empty());
    }
}

TEST(PairList, MalformedListsAreRefused) {
    const auto meshes = randomSoups(3, 4, 10, 0.5);  // the objects point into it
    const auto objects = asObjects(meshes);
    for (const auto& culler : cullers()) {
        Result r;
        using L = std::vector<ObjectIndexPair>;
        EXPECT_THROW(culler->run(objects, L{{1, 1}}, r), std::invalid_argument);            // first == second
        EXPECT_THROW(culler->run(objects, L{{2, 1}}, r), std::invalid_argument);            // first > second
        EXPECT_THROW(culler->run(objects, L{{0, 4}}, r), std::invalid_argument);            // out of range
        EXPECT_THROW(culler->run(objects, L{{0, 2}, {0, 1}}, r), std::invalid_argument);    // unsorted
        EXPECT_THROW(culler->run(objects, L{{0, 1}, {0, 1}}, r), std::invalid_argument);    // repeated
        EXPECT_NO_THROW(culler->run(objects, L{{0, 1}, {2, 3}}, r));
    }
}

}  // namespace
}  // namespace cullide::test
