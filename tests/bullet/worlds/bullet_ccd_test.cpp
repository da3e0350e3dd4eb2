// Continuous collision detection (issue #3), CULLIDE against Bullet's default pipeline: a fast sphere and a fast
// hull stop at a thin plate and at a flat triangle mesh as they do with Bullet.
#include "SceneSupport.h"

#include <gtest/gtest.h>

#include <cstdio>

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

}  // namespace
}  // namespace cullide::test
