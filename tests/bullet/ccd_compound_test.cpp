// Continuous collision detection and a compound that breaks into bodies on impact (issue #3), CULLIDE against
// Bullet's default pipeline.
#include "SceneSupport.h"

#include <BulletCollision/CollisionShapes/btCompoundShape.h>

#include <gtest/gtest.h>

#include <cstdio>
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

/// A convex hull shot at 120 m/s through a flat static triangle mesh (zero thickness): both have triangle
/// geometry, so CULLIDE culls their triangles at the current transforms, while Bullet's CCD sweeps the hull's swept
/// sphere through the broadphase (rayTest with AABB expansion, answered from CULLIDE's btDbvt of the swept AABBs).
void addHullAndMesh(TestWorld& w, ShapeStore& shapes, bool ccd) {
    w.addBody(shapes.landscape(4, btScalar(1.5), 0), 0, btTransform::getIdentity());
    btRigidBody* hull = w.addBody(shapes.hull(btVector3(btScalar(0.12), btScalar(0.1), btScalar(0.11)), 24, 7), 1,
                                  btTransform(btQuaternion(btVector3(1, 0, 1).normalized(), btScalar(0.3)),
                                              btVector3(btScalar(0.2), 2, btScalar(-0.1))));
    hull->setLinearVelocity(btVector3(0, -120, 0));
    if (ccd) {
        hull->setCcdMotionThreshold(btScalar(0.02));
        hull->setCcdSweptSphereRadius(btScalar(0.08));
    }
}

btScalar hullHeightAfterShot(PipelineKind kind, bool ccd) {
    ShapeStore shapes;
    TestWorld w(kind);
    addHullAndMesh(w, shapes, ccd);
    for (int step = 0; step < 30; ++step) w.step();
    return w.objectByIndex(1)->getWorldTransform().getOrigin().y();
}

TEST(BulletCcd, FastHullStopsAtATriangleMeshLikeWithBullet) {
    CULLIDE_BULLET_REQUIRE_GL();
    // Without CCD the hull tunnels through the sheet in both pipelines; with CCD it stays above it in both. Where it
    // comes to rest differs: the impact at 120 m/s is decided by which 4 of the hull-mesh contact points the
    // manifold keeps, and CULLIDE feeds the triangles in sorted order (see the mirrored comparison below).
    EXPECT_LT(hullHeightAfterShot(PipelineKind::Default, false), btScalar(-1));
    EXPECT_LT(hullHeightAfterShot(PipelineKind::Cullide, false), btScalar(-1));
    const btScalar reference = hullHeightAfterShot(PipelineKind::Default, true);
    const btScalar cullide = hullHeightAfterShot(PipelineKind::Cullide, true);
    std::printf("[ccd hull] height after 30 steps: %.4f (default), %.4f (cullide)\n", double(reference),
                double(cullide));
    EXPECT_GT(reference, btScalar(0)) << "Bullet's CCD should stop the hull on the mesh";
    EXPECT_GT(cullide, btScalar(0)) << "the hull tunnelled through the mesh under CULLIDE";
    EXPECT_LT(cullide, btScalar(1));

    // On identical states, step by step, with CCD on: every contact of the default pipeline is there.
    ShapeStore shapes;
    TestWorld a(PipelineKind::Default);
    TestWorld b(PipelineKind::Cullide);
    b.cullideBroadphase()->setConvexMeshCulling(true);  // the hull-mesh triangle path (off by default)
    addHullAndMesh(a, shapes, true);
    addHullAndMesh(b, shapes, true);
    MirrorOptions options;
    options.steps = 60;
    options.tolerance = [](const std::pair<int, int>&) { return double(gContactBreakingThreshold); };
    const MirrorRun run = runMirrored(a, b, options);
    printMirrorRun("ccd hull on a triangle mesh", run);
    expectAgreement(run, 40);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u);
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
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the compound-mesh triangle path (off by default)
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

/// Non-convex bodies made of convex parts, as fracture code makes them: compounds of convex hulls, a box, a sphere
/// and a nested compound, dropped on a triangle-mesh landscape and onto each other. CULLIDE culls each compound
/// as its children's hulls and boxes; the compound algorithm's child-vs-mesh pairs get the mesh's surviving
/// triangles. At step 90 one compound's children are moved (updateChildTransform): its geometry is rebuilt.
TEST(BulletCompound, CompoundsOfHullsOnALandscapeMirrored) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(32, 1, btScalar(1.2));
    btCollisionShape* hullA = shapes.hull(btVector3(btScalar(0.5), btScalar(0.3), btScalar(0.4)), 20, 3);
    btCollisionShape* hullB = shapes.hull(btVector3(btScalar(0.3), btScalar(0.5), btScalar(0.3)), 16, 9);
    btCollisionShape* brick = shapes.box(btVector3(btScalar(0.4), btScalar(0.15), btScalar(0.2)));
    btCollisionShape* ball = shapes.sphere(btScalar(0.25));
    btCompoundShape inner;
    inner.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0, btScalar(0.4), 0)), ball);
    inner.addChildShape(btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.5)), btVector3(0, -btScalar(0.2), 0)),
                        brick);
    btCompoundShape lShape, chain;
    lShape.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(-btScalar(0.5), 0, 0)), hullA);
    lShape.addChildShape(btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(0.8)), btVector3(btScalar(0.3),
                                                                                                btScalar(0.5), 0)),
                         hullB);
    lShape.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(0, 0, btScalar(0.6))), brick);
    chain.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(-btScalar(0.7), 0, 0)), hullB);
    chain.addChildShape(btTransform(btQuaternion(btVector3(1, 0, 0), btScalar(0.7)), btVector3(btScalar(0.2), 0, 0)),
                        &inner);
    chain.addChildShape(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(1.0), btScalar(0.1), 0)), hullA);
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the compound-mesh triangle path (off by default)
    for (TestWorld* w : {&reference, &cullide}) {
        w->addBody(ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 12; ++k)
            w->addBody(k % 2 == 0 ? &lShape : &chain, 2,
                       btTransform(btQuaternion(btVector3(btScalar(0.2), 1, btScalar(0.4)).normalized(),
                                                btScalar(0.7) * btScalar(k)),
                                   btVector3(btScalar(2.2) * btScalar(k % 4) - btScalar(3.3),
                                             btScalar(2.5) + btScalar(1.3) * btScalar(k / 4),
                                             btScalar(1.9) * btScalar((k / 2) % 3) - btScalar(1.9))));
    }
    MirrorOptions options;
    options.steps = 180;
    // Child-vs-landscape contacts come from CULLIDE's triangle list in sorted order: every triangle that makes a
    // contact under Bullet makes it here (checked at triangle level), but each child's persistent 4-point manifold
    // may keep other points, and a point kept from an earlier step stays while within the breaking threshold, so
    // the deepest points of a compound's manifolds can differ by more than one threshold (measured: 0.034 with
    // t = 0.02). Compound-compound pairs run Bullet's algorithms on identical input.
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 ? 2.0 * double(gContactBreakingThreshold) : 1e-6;
    };
    options.before = [&](int step, TestWorld&, TestWorld&) {
        if (step == 90)  // shared shape: both worlds see the change
            chain.updateChildTransform(0, btTransform(btQuaternion::getIdentity(), btVector3(-btScalar(0.9), 0, 0)));
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("compounds of hulls on a landscape", run);
    expectCulledAgreement(run, 1000);  // compound children used the culled lists
    EXPECT_LE(run.cullideTimes.pairs, run.defaultTimes.pairs);
}

}  // namespace
}  // namespace cullide::test
