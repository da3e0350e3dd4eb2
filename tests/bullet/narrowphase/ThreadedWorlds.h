// Two worlds side by side, Bullet's default pipeline and the swap with narrow-phase threads, stepped on their own and
// compared bit for bit; and a mixed GImpact scene (the narrow-phase thread and bit-for-bit tests).
#pragma once

#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <gtest/gtest.h>

#include <cstddef>
#include <functional>
#include <initializer_list>
#include <memory>
#include <vector>

namespace cullide::test {

inline btTransform at(double x, double y, double z, const btQuaternion& q = btQuaternion::getIdentity()) {
    return btTransform(q, btVector3(btScalar(x), btScalar(y), btScalar(z)));
}

/// From step kSleepFrom every body may fall asleep (Bullet's 2 s below the raised thresholds): the piles' pairs are
/// then sleeping pairs, which the dispatch must not collide, on any thread.
inline constexpr int kSleepFrom = 150;

/// The world the threaded swap must match bit for bit, Bullet's default pipeline (`reference`), and the swap with a
/// number of narrow-phase threads (`swap`), both populated by a scene.
struct SideBySide {
    std::unique_ptr<TestWorld> reference = std::make_unique<TestWorld>(PipelineKind::Default);
    TestWorld swap{PipelineKind::Cullide, referenceFactory()};

    template <typename Scene>
    SideBySide(const Scene& scene, unsigned threads) {
        swap.cullideDispatcher()->setNarrowPhaseThreads(threads);
        scene.populate(*reference);
        scene.populate(swap);
    }
};

/// The first of `steps` steps (from now) whose states differ in any bit, or -1; bodies may sleep from kSleepFrom.
inline int firstDivergingStep(TestWorld& reference, TestWorld& w, int steps) {
    return firstDifferingStep(reference, w, steps, kSleepFrom);
}

/// Runs the scene side by side with Bullet's pipeline for `steps` steps with each of the thread counts, expects no
/// bit to differ, then hands the swap's world and its thread count to `check`.
template <typename Scene>
void expectBitForBit(const Scene& scene, std::initializer_list<unsigned> threadCounts, int steps,
                     const std::function<void(TestWorld&, unsigned)>& check) {
    for (const unsigned threads : threadCounts) {
        SideBySide worlds(scene, threads);
        EXPECT_EQ(firstDivergingStep(*worlds.reference, worlds.swap, steps), -1) << threads << " threads";
        check(worlds.swap, threads);
    }
}

/// GImpact tori dropped among spheres, capsules, boxes and hulls onto a BVH landscape and a plane: GImpact pairs
/// against convex shapes and against the landscape whose candidate triangles are often all out of reach.
struct GImpactMixScene {
    ShapeStore shapes;
    btCollisionShape* landscape = shapes.landscape(16, 1, btScalar(0.6));
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), btScalar(-1.5));
    std::vector<btCollisionShape*> kinds{shapes.gimpactTorus(btScalar(0.5), btScalar(0.15), 12, 6, btScalar(0.01)),
                                         shapes.sphere(btScalar(0.3)),
                                         shapes.gimpactTorus(btScalar(0.4), btScalar(0.12), 10, 6, btScalar(0.01)),
                                         shapes.capsule(btScalar(0.2), btScalar(0.5)),
                                         shapes.box(btVector3(0.3f, 0.25f, 0.35f)),
                                         shapes.hull(btVector3(0.4f, 0.3f, 0.35f), 24, 5)};

    void populate(TestWorld& w) const {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(landscape, 0, at(-8, 0, -8));
        w.addBody(plane, 0, at(0, 0, 0));
        int k = 0;
        for (int layer = 0; layer < 3; ++layer)
            for (int i = 0; i < 6; ++i)
                for (int j = 0; j < 6; ++j, ++k) {
                    const btQuaternion turn(btVector3(0.5f, 1, 0.2f).normalized(), btScalar(0.53 * k));
                    w.addBody(kinds[std::size_t(k) % kinds.size()], 1,
                              at(1.2 * (i - 2.5), 2.0 + 1.1 * layer, 1.2 * (j - 2.5), turn));
                }
    }
};

}  // namespace cullide::test
