// The CPU reference of the visibility test (ReferenceVisibility) over a whole culling frame: which triangles each
// iteration of the triangle level prunes, in reliable and sampled mode.
#include "Compare.h"
#include "ReferenceLevelsSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace cullide::test {
namespace {

Result cubeThroughAFace(Mode mode) {
    auto culler = referenceLevelsCuller(referenceLevels(Pipeline::Paper, mode, 32));
    auto meshes = cubesAt({Vec3(0, 0, 0), Vec3(0.8, 0.3, 0.3)});
    for (Vec3& v : meshes[1].vertices) v = Vec3(0.8, 0.3, 0.3) + 0.4 * (v - Vec3(0.8, 0.3, 0.3));
    Result r;
    culler->run(asObjects(meshes), r);
    return r;
}

TEST(ReferenceVisibility, FullyVisibleTrianglesArePrunedIterationByIteration) {
    // A unit cube and a cube of side 0.4 poking through its x = 1 face (x from 0.8 to 1.2). Reliable mode keeps
    // exactly the triangles that can touch the other object: the big cube's x = 1 face and the small cube's four
    // faces that cross it. The first triangle iteration prunes the big cube's other faces (each is in front of
    // everything from its own side); the second prunes the small cube's x = 0.8 face, which was hidden from -x
    // only by the big cube's x = 0 face. Its x = 1.2 face never meets the big cube's box (CPU pre-pass).
    const Result r = cubeThroughAFace(Mode::Reliable);
    ASSERT_EQ(r.pairs.size(), 1u);
    const LevelStats& triangles = r.stats.levels.back();
    ASSERT_EQ(triangles.name, "triangles");
    EXPECT_EQ(triangles.itemsPerIteration, (std::vector<std::size_t>{24, 12, 10}));
    EXPECT_EQ(r.pcsTriangles[0], (std::vector<std::uint32_t>{10, 11}));
    EXPECT_EQ(r.pcsTriangles[1], (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 6, 7}));
    // Sampled mode prunes at least as much. Here it prunes the contact itself: seen along x the small cube's side
    // faces are edge-on and cover no pixel centre, the paper's known miss of contacts thinner than a pixel.
    const Result sampled = cubeThroughAFace(Mode::Sampled);
    for (int o = 0; o < 2; ++o)
        EXPECT_TRUE(std::includes(r.pcsTriangles[o].begin(), r.pcsTriangles[o].end(),
                                  sampled.pcsTriangles[o].begin(), sampled.pcsTriangles[o].end())) << o;
    EXPECT_TRUE(sampled.pairs.empty());
}

}  // namespace
}  // namespace cullide::test
