// Environment 3 of the paper (Environments.h): the bunny and the dragon, procedural stand-ins without the data
// directory, the rigid and the deforming variant, the real meshes when fetched (scripts/fetch_meshes.sh).
#include "MeshChecks.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace cullide::scenes {
namespace {

using namespace cullide::test;

void checkEnv3(Environment& env, std::size_t bunnyTriangles, std::size_t dragonTriangles) {
    const std::vector<TriangleMesh> f0 = env.frame(0);
    ASSERT_EQ(f0.size(), 2u);
    EXPECT_EQ(f0[0].triangles.size(), bunnyTriangles);
    EXPECT_EQ(f0[1].triangles.size(), dragonTriangles);
    for (const auto& m : f0) {
        const double size = boundsOf(m).extent().maxCoeff();
        EXPECT_GT(size, 0.6);
        EXPECT_LT(size, 1.3);
    }
    int intersecting = 0, sampled = 0;
    for (int f = 0; f < 240; f += 10, ++sampled) {
        const auto& meshes = env.frame(f);
        if (anyIntersection(meshes[0], meshes[1])) ++intersecting;
    }
    std::printf("env3: %d of %d sampled frames interpenetrate\n", intersecting, sampled);
    EXPECT_GE(intersecting, sampled * 3 / 4) << intersecting << " of " << sampled << " frames interpenetrate";
}

TEST(Env3, StandInsWhenTheDataDirectoryIsMissing) {
    for (const std::string& dir : {std::string(), std::string("/nonexistent/cullide/data")}) {
        SCOPED_TRACE(dir);
        bool standIns = false;
        auto env = makeEnv3(dir, false, &standIns);
        EXPECT_TRUE(standIns);
        checkEnv3(*env, 75076, 19992);
    }
    EXPECT_NO_THROW(makeEnv3("", true, nullptr));
}

TEST(Env3, RigidBunnyStaticDragonAndTheDeformingVariant) {
    auto rigid = makeEnv3("", false);
    auto deforming = makeEnv3("", true);
    const std::vector<TriangleMesh> r0 = rigid->frame(0), d0 = deforming->frame(0);
    const std::vector<TriangleMesh> r1 = rigid->frame(37), d1 = deforming->frame(37);
    EXPECT_NE(r0[0].vertices, r1[0].vertices);
    EXPECT_LT(shapeChange(r0[0], r1[0]), 1e-9);
    EXPECT_EQ(r0[1].vertices, r1[1].vertices);
    EXPECT_GT(shapeChange(d0[0], d1[0]), 1e-3);
    EXPECT_EQ(d0[1].vertices, d1[1].vertices);
    EXPECT_NE(rigid->name(), "");
}

TEST(Env3, RealMeshesWhenFetched) {
    const std::string dir = defaultDataDir();
    if (!std::filesystem::exists(std::filesystem::path(dir) / "bunny00.off") ||
        !std::filesystem::exists(std::filesystem::path(dir) / "ChineseDragon-10kv.off")) {
        GTEST_SKIP() << "run scripts/fetch_meshes.sh to test the real meshes";
    }
    bool standIns = true;
    auto env = makeEnv3(dir, true, &standIns);
    EXPECT_FALSE(standIns);
    checkEnv3(*env, 75408, 19994);
}

}  // namespace
}  // namespace cullide::scenes
