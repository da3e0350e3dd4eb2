// Environment 1 of the paper (Environments.h): counts, density and containment, determinism for a seed, cylinders
// that move and deform every frame, objects that overlap sometimes.
#include "MeshChecks.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

namespace cullide::scenes {
namespace {

using namespace cullide::test;

TEST(Env1, CountsDensityAndContainment) {
    auto env = makeEnv1(42);
    EXPECT_FALSE(env->name().empty());
    for (const int f : {0, 17, 100, 250, 1000}) {
        SCOPED_TRACE(f);
        const auto& meshes = env->frame(f);
        ASSERT_EQ(meshes.size(), 100u);
        double volume = 0.0;
        for (const TriangleMesh& m : meshes) {
            EXPECT_EQ(m.triangles.size(), 200u);
            volume += cappedVolume(m);
            const Aabb b = boundsOf(m);
            EXPECT_TRUE((b.min.array() >= -1e-9).all() && (b.max.array() <= 1.0 + 1e-9).all());
        }
        // The unit cube has volume 1: the solid volume is the density.
        EXPECT_GE(volume, 0.05);
        EXPECT_LE(volume, 0.06);
    }
}

TEST(Env1, DeterministicForASeedAndFramesInAnyOrder) {
    auto a = makeEnv1(7, 20, 100);
    auto b = makeEnv1(7, 20, 100);
    auto c = makeEnv1(8, 20, 100);
    const std::vector<TriangleMesh> a10 = a->frame(10);
    EXPECT_TRUE(sameMeshes(a10, b->frame(10)));
    EXPECT_FALSE(sameMeshes(a10, c->frame(10)));
    a->frame(3);
    a->frame(500);
    EXPECT_TRUE(sameMeshes(a10, a->frame(10)));
    for (const auto& m : a10) EXPECT_NEAR(static_cast<double>(m.triangles.size()), 100.0, 10.0);
}

TEST(Env1, CylindersMoveAndDeformEveryFrame) {
    auto env = makeEnv1(3, 30);
    const std::vector<TriangleMesh> f0 = env->frame(0);
    const std::vector<TriangleMesh> f1 = env->frame(1);
    const std::vector<TriangleMesh> f20 = env->frame(20);
    for (std::size_t i = 0; i < f0.size(); ++i) {
        for (std::size_t k = 0; k < f0[i].vertices.size(); ++k) {
            ASSERT_NE(f0[i].vertices[k], f1[i].vertices[k]) << "object " << i << " vertex " << k;
        }
        EXPECT_GT(shapeChange(f0[i], f20[i]), 1e-3) << "object " << i << " only moved rigidly";
        EXPECT_GT((boundsOf(f0[i]).min - boundsOf(f20[i]).min).norm(), 1e-3) << "object " << i << " did not move";
    }
}

TEST(Env1, ObjectsOverlapSometimes) {
    auto env = makeEnv1(11);
    int framesWithContact = 0, contacts = 0;
    for (int f = 0; f < 300; f += 30) {
        const auto& meshes = env->frame(f);
        std::vector<Aabb> boxes;
        for (const auto& m : meshes) boxes.push_back(boundsOf(m));
        int here = 0;
        for (std::size_t i = 0; i < meshes.size(); ++i)
            for (std::size_t j = i + 1; j < meshes.size(); ++j)
                if (boxes[i].overlaps(boxes[j]) && anyIntersection(meshes[i], meshes[j])) ++here;
        contacts += here;
        framesWithContact += here > 0 ? 1 : 0;
        // "Sometimes": at 5.5% density random placement makes each cylinder touch about one other on average
        // (~20-70 of the 4950 pairs); nearly all pairs are apart.
        EXPECT_LT(here, 99) << "frame " << f;
    }
    std::printf("env1: %d of 10 frames with contact, %.1f intersecting pairs per frame\n", framesWithContact,
                contacts / 10.0);
    EXPECT_GE(framesWithContact, 3);
    EXPECT_GT(contacts, 0);
}

}  // namespace
}  // namespace cullide::scenes
