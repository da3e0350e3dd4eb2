// Pairs whose broadphase boxes are farther apart than their manifold's contact breaking threshold
// (narrowphase/ApartPairs.h): the dispatcher skips their algorithm and refreshes (for two spheres: clears)
// their manifolds as the algorithm would. Guarded here: the box distance and the threshold (against the manifolds
// Bullet's dispatcher makes); a collision world mirrored in Bullet's default pipeline where objects approach, part,
// sleep and are teleported, with every manifold point compared bit for bit while pairs are skipped; and triggers
// falling through triggers in a dynamics world, bit for bit. The CPU reference culler is used (no GL needed).
#include "narrowphase/ApartPairs.h"
#include "SceneSupport.h"

#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace cullide::test {
namespace {

btVector3 v(double x, double y, double z) { return btVector3(btScalar(x), btScalar(y), btScalar(z)); }

TEST(ApartPairs, BoxDistanceIsEuclideanAndZeroWhenBoxesMeet) {
    const btVector3 lo(0, 0, 0), hi(1, 1, 1);
    EXPECT_EQ(bullet::boxDistanceSquared(lo, hi, v(0.5, 0.5, 0.5), v(2, 2, 2)), btScalar(0));  // overlap
    EXPECT_EQ(bullet::boxDistanceSquared(lo, hi, v(1, 0, 0), v(2, 1, 1)), btScalar(0));        // touching faces
    EXPECT_EQ(bullet::boxDistanceSquared(lo, hi, v(3, 0, 0), v(4, 1, 1)), btScalar(4));        // apart along x
    EXPECT_EQ(bullet::boxDistanceSquared(v(3, 0, 0), v(4, 1, 1), lo, hi), btScalar(4));        // either order
    EXPECT_EQ(bullet::boxDistanceSquared(lo, hi, v(-3, -4, 0.5), v(-2, -3, 2)), btScalar(13));  // corner: 2² + 3²
}

TEST(ApartPairs, ThresholdIsTheOneTheDispatcherGivesTheManifold) {
    ShapeStore shapes;
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btCollisionObject small, large;
    small.setCollisionShape(shapes.sphere(btScalar(0.25)));
    large.setCollisionShape(shapes.hull(v(3, 2.5, 2), 40, 3));
    const int relative = dispatcher.getDispatcherFlags();
    ASSERT_NE(relative & btCollisionDispatcher::CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD, 0);
    for (const int flags : {relative, 0}) {  // relative threshold (Bullet's default), absolute
        dispatcher.setDispatcherFlags(flags);
        for (const auto& [a, b] : {std::pair{&small, &large}, std::pair{&large, &small}, std::pair{&large, &large}}) {
            btPersistentManifold* m = dispatcher.getNewManifold(a, b);
            EXPECT_EQ(bullet::manifoldBreakingThreshold(dispatcher, *a, *b), m->getContactBreakingThreshold());
            dispatcher.releaseManifold(m);
        }
    }
    EXPECT_EQ(bullet::manifoldBreakingThreshold(dispatcher, large, large), gContactBreakingThreshold);
    dispatcher.setDispatcherFlags(relative);
    EXPECT_GT(bullet::manifoldBreakingThreshold(dispatcher, large, large), gContactBreakingThreshold)
        << "a large shape's relative threshold exceeds the AABB expansion";
}

/// Object i's pose at a step. 0-11: a 4 x 3 grid whose neighbours approach until they touch or overlap and part again
/// by up to ~0.5, turning slowly. 12-17: three pairs of axis-aligned boxes 3.8 wide. Pairs 0 and 2 swing their gap
/// through [-0.06, 0.14]: their points at distances between the boxes' expansions (2 x 0.02) and the breaking
/// threshold (~0.059) come from boxes apart. Pair 1 rests in contact; from step 30 (when everything is put to sleep)
/// to 40 its second box is teleported 0.14 away: its box (expanded by 0.02 on each side) 0.09 apart, more than the
/// threshold, but still paired by btDbvtBroadphase's leaves (fattened by 0.05), asleep (Bullet keeps the stale points) and then awake again (from step 36:
/// Bullet's refresh drops them).
btTransform pose(int i, int step) {
    if (i >= 12) {
        const int pair = (i - 12) / 2;
        const bool teleported = pair == 1 && step >= 30 && step < 40;
        const double gap = pair == 1 ? (teleported ? 0.13 : -0.01) : 0.04 + 0.1 * std::cos(0.2 * step + 2.1 * pair);
        // Pair 1 shifts by 0.002 in its first steps: btDbvtBroadphase fattens a leaf only when it moves.
        const double x = (i % 2 == 0 ? 0.0 : 3.8 + gap) + (pair == 1 ? 0.001 * std::min(step, 2) : 0.0);
        return btTransform(btQuaternion::getIdentity(), v(x - 10, 0, 6.0 * pair));
    }
    const double phase = 0.23 * step + 0.9 * i;
    const btQuaternion turn(btVector3(btScalar(0.2), 1, btScalar(0.1)).normalized(), btScalar(0.05 * step + 0.3 * i));
    return btTransform(turn, v((i % 4) * 4.3 + 0.25 * std::sin(phase), 0.1 * (i / 4), (i / 4) * 4.3 +
                                                                                          0.25 * std::cos(phase)));
}

struct Tally {
    std::size_t pairSteps = 0, mismatches = 0, missing = 0, extra = 0;
    std::size_t manifoldCountDiffers = 0;  ///< steps whose dispatchers hold different numbers of manifolds
    std::size_t pointsFromApartBoxes = 0;  ///< Bullet's pair-steps with points although the proxies' boxes are apart
};

void compare(CollisionOnlyWorld& reference, CollisionOnlyWorld& cullide, Tally& t) {
    const ContactMap want = contactsOf(reference.world());
    const ContactMap got = contactsOf(cullide.world());
    for (const auto& [key, pc] : want) {
        ++t.pairSteps;
        const btBroadphaseProxy* p0 = reference.object(static_cast<std::size_t>(key.first)).getBroadphaseHandle();
        const btBroadphaseProxy* p1 = reference.object(static_cast<std::size_t>(key.second)).getBroadphaseHandle();
        if (bullet::boxDistanceSquared(p0->m_aabbMin, p0->m_aabbMax, p1->m_aabbMin, p1->m_aabbMax) > 0)
            ++t.pointsFromApartBoxes;
        const auto it = got.find(key);
        if (it == got.end()) {
            ++t.missing;
            continue;
        }
        const PairContacts& g = it->second;
        if (g.points != pc.points || g.positionsOnB != pc.positionsOnB || g.normalsOnB != pc.normalsOnB ||
            g.distances != pc.distances)
            ++t.mismatches;
    }
    for (const auto& [key, pc] : got) t.extra += want.count(key) ? 0 : 1;
    // Skipped pairs keep their algorithm and (empty) manifolds, as in Bullet: what the island manager reads.
    if (reference.dispatcher().getNumManifolds() != cullide.dispatcher().getNumManifolds()) ++t.manifoldCountDiffers;
}

TEST(ApartPairs, SkippedPairsKeepBulletsPointsBitForBit) {
    ShapeStore shapes;
    // Large shapes: their size-relative breaking threshold (0.02 x the angular motion disc, ~0.05-0.09) exceeds
    // the two boxes' 0.02 expansions, so Bullet makes points between objects whose boxes are apart.
    btCollisionShape* kinds[] = {shapes.hull(v(2.0, 1.6, 1.8), 40, 5), shapes.box(v(1.9, 1.5, 1.7)),
                                 shapes.sphere(btScalar(1.9)), shapes.capsule(btScalar(1.2), btScalar(1.4))};
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    for (CollisionOnlyWorld* w : {&reference, &cullide})
        for (int i = 0; i < 18; ++i) w->add(kinds[i < 12 ? i % 4 : 1], pose(i, 0));
    Tally t;
    for (int step = 0; step < 60; ++step) {
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            for (std::size_t i = 0; i < w->size(); ++i) {
                btCollisionObject& o = w->object(i);
                if (step == 30) o.setActivationState(ISLAND_SLEEPING);  // both asleep: points kept as they are
                if (step == 36) o.setActivationState(ACTIVE_TAG);
                o.setWorldTransform(pose(static_cast<int>(i), step));
            }
            w->world().performDiscreteCollisionDetection();
        }
        compare(reference, cullide, t);
    }
    const std::size_t apart = static_cast<CullideCollisionDispatcher&>(cullide.dispatcher()).getTotalStats().apartPairs;
    std::printf("[ measure  ] apart pairs: %zu pair-steps with contacts (%zu with boxes apart), %zu pair-steps "
                "skipped, missing %zu, extra %zu, point mismatches %zu\n",
                t.pairSteps, t.pointsFromApartBoxes, apart, t.missing, t.extra, t.mismatches);
    EXPECT_GT(t.pairSteps, 100u) << "scene too sparse";
    EXPECT_GE(t.pointsFromApartBoxes, 3u) << "the scene must have points between objects whose boxes are apart";
    EXPECT_GT(apart, 30u) << "the dispatcher must skip pairs here";
    EXPECT_EQ(t.missing, 0u);
    EXPECT_EQ(t.extra, 0u);
    EXPECT_EQ(t.mismatches, 0u);
    EXPECT_EQ(t.manifoldCountDiffers, 0u);
}

/// A scene where Bullet finds points although the proxies' boxes are apart: at least `minimum` such pair-steps, and
/// CULLIDE's points all Bullet's.
void expectBulletsPointsFromApartBoxes(const char* scene, const Tally& t, std::size_t minimum) {
    std::printf("[ measure  ] %s: %zu pair-steps with contacts (%zu with boxes apart), missing %zu, point mismatches "
                "%zu\n",
                scene, t.pairSteps, t.pointsFromApartBoxes, t.missing, t.mismatches);
    EXPECT_GE(t.pointsFromApartBoxes, minimum) << "Bullet must find points here although the boxes are apart";
    EXPECT_EQ(t.missing, 0u);
    EXPECT_EQ(t.extra, 0u);
    EXPECT_EQ(t.mismatches, 0u);
}

// A heightfield's box is the height range the application declares, not computed from its data: where the data
// rises above it, Bullet's default pipeline still finds the points of a box resting there while btDbvtBroadphase's
// fattened leaves pair them, although the two objects' boxes are apart. Such pairs are left to Bullet's algorithm.
TEST(ApartPairs, HeightfieldAboveItsDeclaredRangeKeepsBulletsPoints) {
    constexpr int kSide = 17;
    std::vector<float> heights(kSide * kSide, 0.0f);
    for (int j = 6; j <= 10; ++j)
        for (int i = 6; i <= 10; ++i) heights[static_cast<std::size_t>(j * kSide + i)] = 0.6f;  // a plateau
    // Declared range [-0.5, 0.5]: its box ends (with the world's 0.02 expansion) at 0.52, the plateau at 0.6.
    btHeightfieldTerrainShape field(kSide, kSide, heights.data(), btScalar(-0.5), btScalar(0.5), 1, false);
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(v(0.5, 0.5, 0.5));
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->add(&field, btTransform::getIdentity());
        w->add(box, btTransform::getIdentity());
    }
    Tally t;
    for (int step = 0; step < 12; ++step) {
        // The box settles onto the plateau, 0.03 into it (its bottom at 0.57): its box starts at 0.55, 0.03 above
        // the field's, more than the pair's breaking threshold (~0.019), within btDbvtBroadphase's 0.05 fattening.
        const double bottom = 0.57 + 0.01 * std::max(0, 3 - step);
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            w->object(1).setWorldTransform(btTransform(btQuaternion::getIdentity(), v(0.1, bottom + 0.5, 0.2)));
            w->world().performDiscreteCollisionDetection();
        }
        compare(reference, cullide, t);
    }
    expectBulletsPointsFromApartBoxes("heightfield above its range", t, 6);
}

// Compounds without box trees (btCompoundShape(false)): Bullet's compound-compound algorithm then runs the
// single-compound one it derives from, whose child algorithms (and manifolds) it holds in the base class. A pair
// holding any is never skipped (freed as children part, in Bullet's order); apart with none, it is (a reviewer found
// the base class's children unchecked). Two compounds of boxes slide apart and together; every point and the
// manifold count are compared.
TEST(ApartPairs, CompoundsWithoutTreesKeepBulletsManifolds) {
    ShapeStore shapes;
    // Small parts: the pair's size-relative breaking threshold (~0.01) is well below btDbvtBroadphase's fattening.
    btCollisionShape* part = shapes.box(v(0.3, 0.2, 0.3));
    btCompoundShape a(false), b(false);
    for (btCompoundShape* c : {&a, &b}) {
        c->addChildShape(btTransform(btQuaternion::getIdentity(), v(0, 0.25, 0)), part);
        c->addChildShape(btTransform(btQuaternion::getIdentity(), v(0, -0.25, 0)), part);
    }
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->add(&a, btTransform::getIdentity());
        w->add(&b, btTransform(btQuaternion::getIdentity(), v(0.8, 0, 0)), btBroadphaseProxy::DefaultFilter,
               btBroadphaseProxy::AllFilter)
            ->setCollisionFlags(0);
    }
    btVector3 lo, hi;
    a.getAabb(btTransform::getIdentity(), lo, hi);
    Tally t;
    for (int step = 0; step < 80; ++step) {
        // Two steps 0.02 into each other, then two steps 0.07 apart (their proxies, each grown by 0.02, 0.03 apart:
        // more than the threshold, within btDbvtBroadphase's fattening): the jump apart leaves child algorithms
        // that the next run frees, so that step must not be skipped.
        const double x = double(hi.x() - lo.x()) + (step % 4 < 2 ? -0.02 : 0.07) + 0.0005 * std::min(step, 2);
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            w->object(1).setWorldTransform(btTransform(btQuaternion::getIdentity(), v(x, 0.001 * std::min(step, 2), 0)));
            w->world().performDiscreteCollisionDetection();
        }
        compare(reference, cullide, t);
    }
    const std::size_t skipped = static_cast<CullideCollisionDispatcher&>(cullide.dispatcher()).getTotalStats().apartPairs;
    std::printf("[ measure  ] compounds without trees: %zu pair-steps with contacts, %zu skipped, missing %zu, extra "
                "%zu, point mismatches %zu, manifold counts differing in %zu steps\n",
                t.pairSteps, skipped, t.missing, t.extra, t.mismatches, t.manifoldCountDiffers);
    EXPECT_GT(t.pairSteps, 20u);
    EXPECT_GT(skipped, 5u) << "apart with no child algorithm: skipped";
    EXPECT_EQ(t.missing, 0u);
    EXPECT_EQ(t.extra, 0u);
    EXPECT_EQ(t.mismatches, 0u);
    EXPECT_EQ(t.manifoldCountDiffers, 0u);
}

// A btCylinderShape whose radial half extents differ lies outside its own box: Bullet's support mapping takes one of
// them as the radius for both radial axes, its getAabb each on its own axis (here radius 0.5 along x and z, box 0.2
// along z). Bullet's GJK finds the points where it reaches a box beside it, while btDbvtBroadphase's fattened leaves
// pair them with their boxes apart: such cylinders are never skipped, in every orientation Bullet has (X, Y, Z).
TEST(ApartPairs, CylinderOutsideItsOwnBoxKeepsBulletsPoints) {
    btCylinderShape cylinderY(v(0.5, 0.5, 0.2));   // radius x (0.5), box z 0.2
    btCylinderShapeX cylinderX(v(0.5, 0.5, 0.2));  // radius y (0.5), box z 0.2
    btCylinderShapeZ cylinderZ(v(0.5, 0.2, 0.5));  // radius x (0.5), box y 0.2
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(v(0.5, 0.5, 0.5));
    Tally total;
    for (btCylinderShape* cylinder : {static_cast<btCylinderShape*>(&cylinderY), static_cast<btCylinderShape*>(&cylinderX),
                                      static_cast<btCylinderShape*>(&cylinderZ)}) {
        const int side = cylinder == &cylinderZ ? 1 : 2;  // the short box axis, where the cylinder sticks out
        CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            w->add(cylinder, btTransform::getIdentity());
            w->add(box, btTransform::getIdentity());
        }
        for (int step = 0; step < 12; ++step) {
            // The box's near face from 0.36 to 0.30 on that axis: the cylinder reaches 0.5, its box (with the
            // margin and the world's expansion) ~0.26; the box's proxy starts 0.06 nearer than its face.
            // Once paired, it slides along x: Bullet's GJK makes new points each step, a refresh alone would not.
            btVector3 at(btScalar(0.02 * std::max(0, step - 6)), 0, 0);
            at[side] = btScalar(0.5 + 0.36 - 0.01 * std::min(step, 6));
            for (CollisionOnlyWorld* w : {&reference, &cullide}) {
                w->object(1).setWorldTransform(btTransform(btQuaternion::getIdentity(), at));
                w->world().performDiscreteCollisionDetection();
            }
            compare(reference, cullide, total);
        }
    }
    expectBulletsPointsFromApartBoxes("cylinders outside their own boxes", total, 6);
}

// With setForceUpdateAllAabbs(false) the world refreshes only active objects' proxy boxes. A static box (asleep, as
// Bullet keeps static objects) moved by setWorldTransform alone keeps its old proxy box, while btDbvtBroadphase keeps
// the pair and Bullet's algorithm runs on the moved box: its points must be found, though the proxies are apart.
TEST(ApartPairs, StaticObjectMovedWithoutItsBoxUpdatedKeepsBulletsPoints) {
    ShapeStore shapes;
    btCollisionShape* platform = shapes.box(v(1, 1, 1));
    btCollisionShape* box = shapes.box(v(0.5, 0.5, 0.5));
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->world().setForceUpdateAllAabbs(false);
        w->add(platform, btTransform::getIdentity())->setActivationState(ISLAND_SLEEPING);
        // Proxies 0.03 apart (the box's grown by 0.02), more than the threshold (~0.017): paired once its leaf
        // is fattened (by 0.05).
        btCollisionObject* moving = w->add(box, btTransform(btQuaternion::getIdentity(), v(1.55, 0, 0)),
                                           btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter);
        moving->setCollisionFlags(0);  // not static: the pair is collided while this one is active
    }
    Tally t;
    for (int step = 0; step < 8; ++step) {
        // From step 3 the platform slides towards the box, into it by up to 0.08, its proxy box left where it was.
        // The box shifts by 0.001 in the first steps: btDbvtBroadphase fattens a leaf only when it moves.
        const double x = 0.03 * std::max(0, std::min(step - 2, 5));
        for (CollisionOnlyWorld* w : {&reference, &cullide}) {
            w->object(0).setWorldTransform(btTransform(btQuaternion::getIdentity(), v(x, 0, 0)));
            w->object(1).setWorldTransform(
                btTransform(btQuaternion::getIdentity(), v(1.55 + 0.001 * std::min(step, 2), 0, 0)));
            w->world().performDiscreteCollisionDetection();
        }
        compare(reference, cullide, t);
    }
    expectBulletsPointsFromApartBoxes("static platform moved without its box", t, 3);
    EXPECT_EQ(t.manifoldCountDiffers, 0u);
}

/// Triggers (CF_NO_CONTACT_RESPONSE: sensors, as games use them) falling through static triggers. Once through, the
/// two objects' boxes are apart, yet Bullet's algorithm keeps the points it made on the way in: its refresh measures
/// the distance along each point's normal, which is now negative, and the drift sideways is small. A skipped pair
/// must keep them too, except between two spheres, whose algorithm clears its manifold (one sphere here is fast
/// enough to enter the other in one step and be through in the next, where a refresh would keep the point). Every
/// kind of algorithm the dispatcher may skip is here: sphere-box, box-box, hull-box (GJK), sphere-mesh
/// (convex-concave), sphere-sphere.
class ThroughScene {
public:
    enum Kind { SphereBox, BoxBox, HullBox, SphereMesh, SphereSphere, kKinds };
    static constexpr int kHeights = 4;  // start heights per kind

    ThroughScene()
        : m_plate(m_shapes.box(v(1, 0.05, 1))),
          m_mesh(m_shapes.landscape(4, btScalar(0.5), btScalar(0.02))),
          m_ball(m_shapes.sphere(btScalar(0.6))),
          m_smallBall(m_shapes.sphere(btScalar(0.1))),
          m_cube(m_shapes.box(v(0.1, 0.1, 0.1))),
          m_hull(m_shapes.hull(v(0.12, 0.1, 0.11), 24, 7)) {}

    /// Per kind and start height, a static trigger and a trigger falling through it from rest.
    void populate(TestWorld& w) {
        for (int kind = 0; kind < kKinds; ++kind)
            for (int h = 0; h < kHeights; ++h) {
                const double x = 4.0 * kind, z = 4.0 * h;
                btCollisionShape* still = kind == SphereMesh ? m_mesh : kind == SphereSphere ? m_ball : m_plate;
                btCollisionShape* mover = kind == BoxBox ? m_cube : kind == HullBox ? m_hull : m_smallBall;
                btRigidBody* s = w.addBody(still, 0, btTransform(btQuaternion::getIdentity(), v(x, 2, z)));
                btRigidBody* m =
                    w.addBody(mover, 1, btTransform(btQuaternion::getIdentity(), v(x + 0.05 * h, 2.5 + 0.13 * h, z)));
                m->setActivationState(DISABLE_DEACTIVATION);
                // Two spheres: fast enough to be through in one step, where a refresh would keep the point.
                if (kind == SphereSphere) m->setLinearVelocity(v(0, -80, 0));
                for (btRigidBody* b : {s, m})
                    b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_NO_CONTACT_RESPONSE);
                m_kindOf.resize(static_cast<std::size_t>(w.nextIndex()), -1);
                m_kindOf[static_cast<std::size_t>(m->getUserIndex())] = kind;
            }
    }
    /// The kind of the pair a manifold belongs to (-1: none).
    int kindOf(const btPersistentManifold& m) const {
        for (const btCollisionObject* o : {m.getBody0(), m.getBody1()}) {
            const auto i = static_cast<std::size_t>(o->getUserIndex());
            if (i < m_kindOf.size() && m_kindOf[i] >= 0) return m_kindOf[i];
        }
        return -1;
    }

private:
    ShapeStore m_shapes;
    btCollisionShape *m_plate, *m_mesh, *m_ball, *m_smallBall, *m_cube, *m_hull;
    std::vector<int> m_kindOf;
};

TEST(ApartPairs, PointsOfObjectsGoneThroughEachOtherStayAsInBullet) {
    ThroughScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld swap(PipelineKind::Cullide, referenceFactory());
    scene.populate(reference);
    scene.populate(swap);
    // Per kind: pair-steps in which Bullet's manifold holds a point although the proxies' boxes are farther apart
    // than its threshold (the pairs the swap skips).
    int kept[ThroughScene::kKinds] = {};
    int differing = -1;
    for (int step = 0; step < 90; ++step) {
        if (firstDifferingStep(reference, swap, 1) >= 0 && differing < 0) differing = step;
        btCollisionDispatcher& d = reference.dispatcher();
        for (int i = 0; i < d.getNumManifolds(); ++i) {
            const btPersistentManifold& m = *d.getManifoldByIndexInternal(i);
            const btBroadphaseProxy* p0 = m.getBody0()->getBroadphaseHandle();
            const btBroadphaseProxy* p1 = m.getBody1()->getBroadphaseHandle();
            const btScalar t = m.getContactBreakingThreshold();
            const int kind = scene.kindOf(m);
            if (kind >= 0 && m.getNumContacts() > 0 &&
                bullet::boxDistanceSquared(p0->m_aabbMin, p0->m_aabbMax, p1->m_aabbMin, p1->m_aabbMax) > t * t)
                ++kept[kind];
        }
    }
    const std::size_t skipped = swap.cullideDispatcher()->getTotalStats().apartPairs;
    std::printf("[ measure  ] gone through: Bullet keeps points of apart boxes in %d sphere-box, %d box-box, %d "
                "hull-box, %d sphere-mesh, %d sphere-sphere pair-steps; %zu pair-steps skipped\n",
                kept[ThroughScene::SphereBox], kept[ThroughScene::BoxBox], kept[ThroughScene::HullBox],
                kept[ThroughScene::SphereMesh], kept[ThroughScene::SphereSphere], skipped);
    EXPECT_EQ(differing, -1) << "the swap's bodies or manifolds differ from Bullet's from this step";
    for (const int kind : {ThroughScene::SphereBox, ThroughScene::BoxBox, ThroughScene::HullBox,
                           ThroughScene::SphereMesh})
        EXPECT_GT(kept[kind], 0) << "kind " << kind << ": Bullet must keep a point of objects gone through";
    EXPECT_EQ(kept[ThroughScene::SphereSphere], 0) << "Bullet's sphere-sphere algorithm clears its manifold";
    EXPECT_GT(skipped, 20u) << "the dispatcher must skip these pairs";
}

}  // namespace
}  // namespace cullide::test
