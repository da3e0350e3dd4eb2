// Continuous collision detection and a compound that breaks into bodies on impact (issue #3), CULLIDE against
// Bullet's default pipeline.
#include "SceneSupport.h"

#include <BulletCollision/CollisionShapes/btCompoundShape.h>

#include <gtest/gtest.h>

#include <memory>

namespace cullide::test {
namespace {

/// A small sphere shot at 120 m/s through a 2 cm static plate. With CCD Bullet's predictive sweep stops it; the
/// sweep queries the broadphase (rayTest with AABB expansion), which CULLIDE answers from its own btDbvt.
btScalar shootThroughPlate(PipelineKind kind, bool ccd) {
    ShapeStore shapes;
    TestWorld w(kind);
    w.addBody(shapes.box(btVector3(3, btScalar(0.01), 3)), 0, btTransform::getIdentity());
    btRigidBody* bullet =
        w.addBody(shapes.sphere(btScalar(0.05)), 1, btTransform(btQuaternion::getIdentity(), btVector3(0, 2, 0)));
    bullet->setLinearVelocity(btVector3(0, -120, 0));
    if (ccd) {
        bullet->setCcdMotionThreshold(btScalar(0.02));
        bullet->setCcdSweptSphereRadius(btScalar(0.04));
    }
    for (int step = 0; step < 30; ++step) w.step();
    return bullet->getWorldTransform().getOrigin().y();
}

TEST(BulletCcd, FastSphereStopsAtAThinPlateLikeWithBullet) {
    CULLIDE_BULLET_REQUIRE_GL();
    // Without CCD the sphere tunnels (2 m per step against a 2 cm plate) in both pipelines: the scene can fail.
    EXPECT_LT(shootThroughPlate(PipelineKind::Default, false), btScalar(-1));
    EXPECT_LT(shootThroughPlate(PipelineKind::Cullide, false), btScalar(-1));
    const btScalar reference = shootThroughPlate(PipelineKind::Default, true);
    const btScalar cullide = shootThroughPlate(PipelineKind::Cullide, true);
    EXPECT_GT(reference, btScalar(0)) << "Bullet's CCD should stop the sphere on the plate";
    EXPECT_GT(cullide, btScalar(0)) << "the sphere tunnelled through the plate under CULLIDE";
    EXPECT_NEAR(double(cullide), double(reference), 1e-5);
}

/// A compound of four boxes falls on a box floor and, at step kBreakStep (just after landing), is replaced in both
/// worlds by four bodies at its children's places with its velocity — what fracture code does.
TEST(BulletCompound, CompoundBreaksIntoBodiesMirrored) {
    CULLIDE_BULLET_REQUIRE_GL();
    constexpr int kBreakStep = 52;
    ShapeStore shapes;
    btCollisionShape* floor = shapes.box(btVector3(10, 1, 10));
    btCollisionShape* brick = shapes.box(btVector3(btScalar(0.5), btScalar(0.25), btScalar(0.25)));
    btCollisionShape* ball = shapes.sphere(btScalar(0.3));
    btCompoundShape compound;
    btTransform children[4];
    for (int k = 0; k < 4; ++k) {
        children[k] = btTransform(btQuaternion::getIdentity(),
                                  btVector3(btScalar(k % 2) - btScalar(0.5), btScalar(k / 2) * btScalar(0.5), 0));
        compound.addChildShape(children[k], brick);
    }
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    for (TestWorld* w : {&reference, &cullide}) {
        w->addBody(floor, 0, btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)));
        w->addBody(&compound, 4,
                   btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.3)), btVector3(0, 3, 0)));  // index 1
        w->addBody(ball, 1, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.2), 5, 0)));
    }
    int piecesAdded = 0;
    MirrorOptions options;
    options.steps = 180;
    options.before = [&](int step, TestWorld& a, TestWorld& b) {
        if (step != kBreakStep) return;
        for (TestWorld* w : {&a, &b}) {
            btRigidBody* whole = btRigidBody::upcast(w->objectByIndex(1));
            const btTransform t = whole->getWorldTransform();
            const btVector3 v = whole->getLinearVelocity(), omega = whole->getAngularVelocity();
            w->removeBody(whole);
            for (const btTransform& child : children) {
                btRigidBody* piece = w->addBody(brick, 1, t * child);
                piece->setLinearVelocity(v + omega.cross(t.getBasis() * child.getOrigin()));
                piece->setAngularVelocity(omega);
                ++piecesAdded;
            }
        }
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("breaking compound", run);
    EXPECT_EQ(piecesAdded, 8);
    expectAgreement(run, 150);
}

}  // namespace
}  // namespace cullide::test
