// Bullet as a collision library: a btCollisionWorld of plain btCollisionObjects (static-flagged by default, as
// Bullet constructs them), mirrored in a world with Bullet's default pipeline. Pairs are decided by the filter
// alone, as in Bullet: static-static pairs exist, flags switched between steps change nothing, group/mask and an
// overlap filter callback are honoured. The CPU reference culler is used (no GL needed).
#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace cullide::test {
namespace {

/// Rejects pairs of two objects whose user indices are both multiples of 3 (an application's own rule).
struct SkipMultiplesOfThree : btOverlapFilterCallback {
    bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
        if ((p0->m_collisionFilterGroup & p1->m_collisionFilterMask) == 0 ||
            (p1->m_collisionFilterGroup & p0->m_collisionFilterMask) == 0)
            return false;
        const int a = static_cast<btCollisionObject*>(p0->m_clientObject)->getUserIndex();
        const int b = static_cast<btCollisionObject*>(p1->m_clientObject)->getUserIndex();
        return a % 3 != 0 || b % 3 != 0;
    }
};

struct Counts {
    std::size_t pairSteps = 0;        ///< pair-steps with contacts under the default pipeline
    std::size_t staticStatic = 0;     ///< ... between two static-flagged objects
    std::size_t missing = 0, extra = 0;
    std::size_t convexPairSteps = 0, pointMismatches = 0;  ///< convex-convex pairs, and those whose points differ
    double maxMeshDepthDifference = 0.0;                    ///< pairs with a mesh: largest deepest-point difference
};

/// A collision world scene: boxes, spheres, hulls, GImpact tori, a BVH landscape and a plane, all plain
/// collision objects, moved and re-flagged between detections; contacts compared pair by pair.
Counts runScene(bool filterCallback) {
    ShapeStore shapes;
    auto v = [](double x, double y, double z) { return btVector3(btScalar(x), btScalar(y), btScalar(z)); };
    btCollisionShape* kinds[] = {shapes.box(v(0.5, 0.4, 0.6)), shapes.sphere(btScalar(0.5)),
                                 shapes.hull(v(0.6, 0.5, 0.4), 40, 7),
                                 shapes.gimpactTorus(btScalar(0.6), btScalar(0.2), 16, 8, btScalar(0.01))};
    btCollisionShape* landscape = shapes.landscape(16, btScalar(1.0), btScalar(0.6));
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), btScalar(-2));
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    SkipMultiplesOfThree callback;
    if (filterCallback) {
        reference.world().getPairCache()->setOverlapFilterCallback(&callback);
        cullide.world().getPairCache()->setOverlapFilterCallback(&callback);
    }
    auto place = [](int i, int step) {
        const double phase = 0.37 * i + 0.11 * step;
        btTransform t(btQuaternion(btVector3(btScalar(0.3), 1, btScalar(0.2)).normalized(), btScalar(phase)),
                      btVector3(btScalar(-6 + (i % 6) * 1.05 + 0.3 * std::sin(phase)), btScalar(0.4 + 0.25 * (i % 3)),
                                btScalar(-6 + (i / 6) * 1.1 + 0.3 * std::cos(phase))));
        return t;
    };
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->add(landscape, btTransform(btQuaternion::getIdentity(), btVector3(-8, 0, -8)), 1, -1);
        w->add(plane, btTransform::getIdentity(), 1, -1);
        for (int i = 0; i < 40; ++i) {
            // Groups 1 and 2; group 2 objects ignore each other (mask without 2).
            const int group = i % 5 == 4 ? 2 : 1;
            const int mask = group == 2 ? ~2 : -1;
            w->add(kinds[i % 4], place(i, 0), group, mask);
        }
    }
    Counts c;
    for (int step = 0; step < 24; ++step) {
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            for (std::size_t i = 2; i < w->size(); ++i) {
                btCollisionObject& o = w->object(i);
                o.setWorldTransform(place(static_cast<int>(i) - 2, step));
                // All static-flagged at first (Bullet's default for a btCollisionObject), then flags switched
                // between steps: static, kinematic, plain (Bullet's pairs ignore them).
                const int flagsKind = step < 6 ? 0 : (static_cast<int>(i) + step / 4) % 3;
                o.setCollisionFlags(flagsKind == 0 ? btCollisionObject::CF_STATIC_OBJECT
                                                   : flagsKind == 1 ? btCollisionObject::CF_KINEMATIC_OBJECT : 0);
            }
            w->world().performDiscreteCollisionDetection();
        }
        const ContactMap want = contactsOf(reference.world());
        const ContactMap got = contactsOf(cullide.world());
        for (const auto& [key, pc] : want) {
            ++c.pairSteps;
            if (reference.object(static_cast<std::size_t>(key.first)).isStaticObject() &&
                reference.object(static_cast<std::size_t>(key.second)).isStaticObject())
                ++c.staticStatic;
            const auto it = got.find(key);
            if (it == got.end()) {
                ++c.missing;
                continue;
            }
            // Pairs of convex objects run Bullet's algorithm on identical input: identical points. A mesh's pairs
            // get the same triangles in another order, so its 4-point manifolds may keep other points (compared
            // point by point in the mirrored dynamics tests); here their pairs must match.
            const bool meshPair = key.first == 0 || (key.first - 2) % 4 == 3 || (key.second - 2) % 4 == 3;
            if (meshPair) {
                c.maxMeshDepthDifference = std::max(c.maxMeshDepthDifference,
                                                    std::abs(it->second.minDistance - pc.minDistance));
                continue;
            }
            ++c.convexPairSteps;
            if (it->second.points != pc.points || std::abs(it->second.minDistance - pc.minDistance) > 1e-6)
                ++c.pointMismatches;
        }
        for (const auto& [key, pc] : got) c.extra += want.count(key) ? 0 : 1;
    }
    return c;
}

TEST(CollisionWorld, PlainCollisionObjectsPairAsInBullet) {
    const Counts c = runScene(false);
    std::printf("[ measure  ] collision world: %zu pair-steps with contacts (%zu static-static), missing %zu, "
                "extra %zu, convex pair-steps %zu with %zu point mismatches, mesh pairs' deepest points within %.3g\n",
                c.pairSteps, c.staticStatic, c.missing, c.extra, c.convexPairSteps, c.pointMismatches,
                c.maxMeshDepthDifference);
    EXPECT_GT(c.convexPairSteps, 100u);
    EXPECT_GT(c.pairSteps, 200u) << "scene too sparse to test anything";
    EXPECT_GT(c.staticStatic, 50u) << "the scene must have static-static contacts";
    EXPECT_EQ(c.missing, 0u);
    EXPECT_EQ(c.extra, 0u);
    EXPECT_EQ(c.pointMismatches, 0u);
}

TEST(CollisionWorld, OverlapFilterCallbackIsHonoured) {
    const Counts c = runScene(true);
    EXPECT_GT(c.pairSteps, 150u);
    EXPECT_EQ(c.missing, 0u);
    EXPECT_EQ(c.extra, 0u);
    EXPECT_EQ(c.pointMismatches, 0u);
}

}  // namespace
}  // namespace cullide::test
