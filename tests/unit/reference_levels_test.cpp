// Every level of both pipelines on the reference backend against the exact culler on random soups, at several
// resolutions in both modes: reliable mode misses nothing, both modes prune.
#include "Compare.h"
#include "ReferenceLevelsSupport.h"

#include <gtest/gtest.h>

#include <ostream>
#include <string>

namespace cullide::test {
namespace {

struct Case {
    Pipeline pipeline;
    Mode mode;
    int resolution;
};

std::string name(const Case& c) {
    return std::string(c.pipeline == Pipeline::Paper ? "Paper" : "Auto") +
           (c.mode == Mode::Reliable ? "Reliable" : "Sampled") + std::to_string(c.resolution);
}
std::string caseName(const ::testing::TestParamInfo<Case>& param) { return name(param.param); }
void PrintTo(const Case& c, std::ostream* os) { *os << name(c); }

class ReferenceLevels : public ::testing::TestWithParam<Case> {};

TEST_P(ReferenceLevels, ReliableMissesNothingAndBothModesPrune) {
    const Case c = GetParam();
    auto culler = referenceLevelsCuller(referenceLevels(c.pipeline, c.mode, c.resolution));
    auto exact = createReferenceCuller(Settings{});
    std::size_t missed = 0, expected = 0, in = 0, out = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        const auto meshes = randomSoups(seed, 12, 60, 0.2);
        const auto objects = asObjects(meshes);
        Result truth, got;
        exact->run(objects, truth);
        culler->run(objects, got);
        const Comparison cmp = compare(truth, got);
        missed += cmp.missed;
        expected += cmp.expected;
        EXPECT_EQ(cmp.spurious, 0u);
        for (const LevelStats& level : got.stats.levels) {
            if (level.itemsPerIteration.empty()) continue;  // a level with nothing left to prune
            in += level.itemsPerIteration.front();
            out += level.itemsPerIteration.back();
        }
    }
    EXPECT_GT(expected, 0u);
    if (c.mode == Mode::Reliable) {
        EXPECT_EQ(missed, 0u);
    }
    EXPECT_LT(out, in / 2) << "the levels must prune: " << out << " of " << in << " items survive";
}

INSTANTIATE_TEST_SUITE_P(Matrix, ReferenceLevels,
                         ::testing::Values(Case{Pipeline::Auto, Mode::Reliable, 16}, Case{Pipeline::Auto, Mode::Reliable, 128},
                                           Case{Pipeline::Paper, Mode::Reliable, 16}, Case{Pipeline::Paper, Mode::Reliable, 128},
                                           Case{Pipeline::Auto, Mode::Sampled, 64}, Case{Pipeline::Paper, Mode::Sampled, 64}),
                         caseName);

}  // namespace
}  // namespace cullide::test
