// Bullet's solver reads the manifolds in the dispatcher's order, empty ones included (the islands are sorted by an
// unstable sort), so the swap must make and free every manifold, empty or not, where Bullet does. Two places where it
// skips Bullet's work are guarded here: pairs whose boxes are apart (narrowphase/ApartPairs.h: a compound algorithm
// run there frees its children's manifolds), and GImpact against convex shapes and meshes, whose trimmed loops skip
// triangles that cannot make a point (Bullet's loop makes the pair's manifold at its first candidate triangle, point
// or not). The CPU reference culler is used (no GL needed).
#include "ThreadedWorlds.h"

#include <BulletCollision/CollisionShapes/btCompoundShape.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <vector>

namespace cullide::test {
namespace {

/// Compounds of one or two boxes bouncing (restitution 0.9) on a ground box and off each other: children stop
/// touching the other shape from one step to the next, farther apart than the contact breaking threshold.
struct BouncingCompoundScene {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.box(btVector3(12, 0.5f, 12));
    std::vector<std::unique_ptr<btCompoundShape>> compounds;

    BouncingCompoundScene() {
        for (int k = 0; k < 2; ++k) {
            compounds.push_back(std::make_unique<btCompoundShape>());
            compounds.back()->addChildShape(at(0, 0, 0), shapes.box(btVector3(0.4f, 0.2f, 0.3f)));
            if (k == 1) compounds.back()->addChildShape(at(0.5, 0.3, 0), shapes.box(btVector3(0.15f, 0.3f, 0.15f)));
        }
    }

    void populate(TestWorld& w) const {
        w.addBody(ground, 0, at(0, -0.5, 0))->setRestitution(btScalar(0.9));
        for (int i = 0; i < 8; ++i)
            for (int j = 0; j < 8; ++j) {
                const int k = i * 8 + j;
                const btQuaternion turn(btVector3(0.2f, 1, 0.3f).normalized(), btScalar(0.43 * k));
                w.addBody(compounds[std::size_t(k % 2)].get(), 1,
                          at(1.1 * (i - 3.5), 1.0 + 0.7 * (k % 3), 1.1 * (j - 3.5), turn))
                    ->setRestitution(btScalar(0.9));
            }
    }
};

TEST(BitForBit, BouncingCompoundsKeepBulletsManifolds) {
    expectBitForBit(BouncingCompoundScene{}, {1u, 2u}, 150, [](TestWorld& w, unsigned) {
        EXPECT_GT(w.cullideDispatcher()->getTotalStats().apartPairs, 100u) << "pairs apart are skipped";
    });
}

TEST(BitForBit, GImpactAgainstConvexAndMeshKeepsBulletsManifolds) {
    expectBitForBit(GImpactMixScene{}, {1u, 2u, 5u}, 150, [](TestWorld& w, unsigned threads) {
        const CullideDispatchStats& stats = w.cullideDispatcher()->getTotalStats();
        std::printf("[ measure  ] %u threads: %zu GImpact-convex pair-steps, %zu computed ahead on the workers\n",
                    threads, stats.convexPairs, stats.threadedConvexPairs);
        EXPECT_GT(stats.convexPairs, 500u);
        EXPECT_GT(stats.concavePairs, 100u);
        EXPECT_LT(stats.convexTriangles, stats.convexCandidates) << "candidate triangles out of reach are skipped";
        if (threads == 1)
            EXPECT_EQ(stats.threadedConvexPairs, 0u);
        else
            EXPECT_GT(stats.threadedConvexPairs, stats.convexPairs / 2)
                << "GImpact-convex pairs are computed on the narrow-phase threads, their points added in order";
    });
}

}  // namespace
}  // namespace cullide::test
