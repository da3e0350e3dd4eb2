// Environment 2 of the paper (Environments.h): tori counts, orientation, deformation and determinism; density and
// occasional collisions.
#include "MeshChecks.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

namespace cullide::scenes {
namespace {

using namespace cullide::test;

TEST(Env2, ToriCountsOrientationDeformationAndDeterminism) {
    auto env = makeEnv2(42);
    const std::vector<TriangleMesh> f0 = env->frame(0);
    ASSERT_EQ(f0.size(), 6u);
    for (const TriangleMesh& m : f0) {
        EXPECT_NEAR(static_cast<double>(m.triangles.size()), 20000.0, 200.0);
        EXPECT_TRUE(isClosedOriented(m));
        EXPECT_GT(signedVolume(m), 0.0);
    }
    const std::vector<TriangleMesh> f1 = env->frame(1);
    const std::vector<TriangleMesh> f15 = env->frame(15);
    for (std::size_t i = 0; i < f0.size(); ++i) {
        EXPECT_NE(f0[i].vertices, f1[i].vertices);
        EXPECT_GT(shapeChange(f0[i], f15[i]), 1e-3) << "torus " << i << " only moved rigidly";
    }
    EXPECT_TRUE(sameMeshes(f15, makeEnv2(42)->frame(15)));
    EXPECT_FALSE(sameMeshes(f15, makeEnv2(43)->frame(15)));
}

TEST(Env2, DensityAndOccasionalCollisions) {
    auto env = makeEnv2(5, 6, 4000);  // fewer triangles keep the intersection checks quick
    Aabb all;
    double volume = 0.0;
    int framesWithContact = 0, contactPairs = 0;
    const int frames = 40;
    for (int f = 0; f < frames * 15; f += 15) {
        const auto& meshes = env->frame(f);
        double v = 0.0;
        for (const auto& m : meshes) {
            v += signedVolume(m);
            all.grow(boundsOf(m));
        }
        volume += v / frames;
        int here = 0;
        for (std::size_t i = 0; i < meshes.size(); ++i)
            for (std::size_t j = i + 1; j < meshes.size(); ++j) here += anyIntersection(meshes[i], meshes[j]) ? 1 : 0;
        framesWithContact += here > 0 ? 1 : 0;
        contactPairs += here;
    }
    // The tori stay in a cube of side L; the region they sweep is at most that cube, so this ratio is an upper
    // estimate of the 6-8% density: it is at least the density and close to it once the walls are reached.
    const double swept = all.extent().prod();
    EXPECT_GE(volume / swept, 0.06);
    EXPECT_LE(volume / swept, 0.12);
    // Colliding sometimes: contacts happen, but most of the 15 pairs are apart at any time.
    std::printf("env2: %d of %d frames with contact, %.2f pairs per frame\n", framesWithContact, frames,
                static_cast<double>(contactPairs) / frames);
    EXPECT_GE(framesWithContact, 2);
    EXPECT_LT(contactPairs, frames * 15 / 2);
}

}  // namespace
}  // namespace cullide::scenes
