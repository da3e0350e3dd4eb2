// Random scenes (Procedural.h): deterministic, inside their box and mixed; closed shapes only without soups; a fair
// fraction of objects intersecting.
#include "MeshChecks.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace cullide::scenes {
namespace {

using namespace cullide::test;

TEST(RandomScene, DeterministicInTheBoxAndMixed) {
    RandomSceneOptions o;
    o.objects = 40;
    const auto a = makeRandomScene(99, o);
    EXPECT_TRUE(sameMeshes(a, makeRandomScene(99, o)));
    EXPECT_FALSE(sameMeshes(a, makeRandomScene(100, o)));
    ASSERT_EQ(a.size(), 40u);
    int degenerate = 0, open = 0;
    for (const TriangleMesh& m : a) {
        EXPECT_GE(m.triangles.size(), static_cast<std::size_t>(o.minTriangles / 2));
        EXPECT_LE(m.triangles.size(), static_cast<std::size_t>(o.maxTriangles * 6 / 5));
        const Aabb b = boundsOf(m);
        EXPECT_TRUE((b.min.array() >= -1e-9).all() && (b.max.array() <= o.boxSize + 1e-9).all());
        for (const auto& t : m.triangles) {
            const Vec3 n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
            if (n.norm() < 1e-12) ++degenerate;
        }
        if (!isClosedOriented(m)) ++open;
    }
    EXPECT_GT(degenerate, 0);
    EXPECT_GT(open, 0);
}

TEST(RandomScene, ClosedShapesOnlyWithoutSoups) {
    RandomSceneOptions o;
    o.objects = 30;
    o.soups = false;
    for (const TriangleMesh& m : makeRandomScene(5, o)) {
        EXPECT_TRUE(isClosedOriented(m));
        EXPECT_GT(signedVolume(m), 0.0);
    }
    o.objects = 0;
    EXPECT_TRUE(makeRandomScene(5, o).empty());
    o.objects = -1;
    EXPECT_THROW(makeRandomScene(5, o), std::invalid_argument);
}

TEST(RandomScene, AFairFractionOfObjectsIntersect) {
    RandomSceneOptions o;
    o.objects = 20;
    int inContact = 0, total = 0;
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
        const auto scene = makeRandomScene(seed, o);
        std::vector<bool> touched(scene.size(), false);
        for (std::size_t i = 0; i < scene.size(); ++i)
            for (std::size_t j = i + 1; j < scene.size(); ++j)
                if (anyIntersection(scene[i], scene[j])) touched[i] = touched[j] = true;
        inContact += static_cast<int>(std::count(touched.begin(), touched.end(), true));
        total += static_cast<int>(scene.size());
    }
    EXPECT_GE(inContact, total / 5);
    EXPECT_LE(inContact, total * 9 / 10);
}

}  // namespace
}  // namespace cullide::scenes
