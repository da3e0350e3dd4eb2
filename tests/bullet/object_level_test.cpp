// The broadphase's object level (issue #12, item 3): pairs from the overlapping boxes of an incremental tree, the
// CULLIDE levels only for pairs whose narrow phase reads triangles, and the culler's verdict deciding those pairs.
#include "SceneSupport.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <gtest/gtest.h>

namespace cullide::test {
namespace {

btTransform at(double x, double y, double z, const btQuaternion& q = btQuaternion::getIdentity()) {
    return btTransform(q, btVector3(btScalar(x), btScalar(y), btScalar(z)));
}

/// Two GImpact tori (radius 2, tube 0.2): the first flat, the second upright with its lowest point dipping into the
/// first's hole, far from its tube. Their boxes overlap, their meshes are apart: the culler proves the pair
/// farther than its margin, so no pair reaches the narrow phase. Moved onto the first's tube (0.002 above it),
/// the pair is back, with triangles.
TEST(ObjectLevel, CulledPairIsDecidedByTheCuller) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(2, btScalar(0.2), 32, 8, btScalar(0.01));
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
    w.world().setGravity(btVector3(0, 0, 0));
    w.addBody(torus, 1, at(0, 0, 0));
    const btQuaternion upright(btVector3(1, 0, 0), SIMD_HALF_PI);  // lowest point at (0, -2.2, 0) from its centre
    btRigidBody* other = w.addBody(torus, 1, at(0, 2.3, 0, upright));
    w.detectCollisions();
    const CullideFrameStats& s = w.cullideBroadphase()->getLastFrameStats();
    EXPECT_EQ(s.objectPairs, 1u);
    EXPECT_EQ(s.culledPairs, 1u);
    EXPECT_EQ(s.prunedPairs, 1u);
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 0);

    // Lowest vertex (2, 0.202, 0), right above the first's top vertex (2, 0.2, 0).
    btTransform near = at(2, 2.2 + 0.202, 0, upright);
    other->setWorldTransform(near);
    w.detectCollisions();
    const CullideFrameStats& t = w.cullideBroadphase()->getLastFrameStats();
    EXPECT_EQ(t.culledPairs, 1u);
    EXPECT_EQ(t.prunedPairs, 0u);
    EXPECT_GT(t.trianglePairs, 0u);
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 1);
}

/// Hulls, boxes and spheres on a BVH mesh: nobody reads their triangles (convex-mesh culling is off by default), so
/// the culler gets nothing and every pair comes from the object level, exactly the boxes' overlaps.
TEST(ObjectLevel, PairsWhoseTrianglesNobodyReadsSkipTheCuller) {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(8, 1, btScalar(0.3));
    btCollisionShape* hull = shapes.hull(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)), 24, 3);
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.4), btScalar(0.4), btScalar(0.4)));
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    for (TestWorld* x : {&reference, &w}) {
        x->addBody(ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 12; ++k)
            x->addBody(k % 2 ? hull : box, 1, at(-3 + (k % 4) * 0.7, 0.4 + (k / 4) * 0.6, 0.5 * (k % 3)));
        x->detectCollisions();
    }
    const CullideFrameStats& s = w.cullideBroadphase()->getLastFrameStats();
    EXPECT_GT(s.objectPairs, 10u);
    EXPECT_EQ(s.culledPairs, 0u);
    EXPECT_EQ(s.culledObjects, 0u);
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(),
              reference.broadphase().getOverlappingPairCache()->getNumOverlappingPairs());
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), static_cast<int>(s.objectPairs));

    w.cullideBroadphase()->setConvexMeshCulling(true);
    w.detectCollisions();
    EXPECT_GT(w.cullideBroadphase()->getLastFrameStats().culledPairs, 0u) << "hull-mesh pairs culled when asked";
}

/// A body that turns static (and back) moves between the object level's trees and keeps its pairs.
TEST(ObjectLevel, FlagChangesMoveProxiesBetweenTrees) {
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    btRigidBody* a = w.addBody(box, 1, at(0, 0, 0));
    w.addBody(box, 1, at(0.9, 0, 0));
    w.detectCollisions();
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    a->setCollisionFlags(a->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    w.detectCollisions();
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    a->setCollisionFlags((a->getCollisionFlags() & ~btCollisionObject::CF_KINEMATIC_OBJECT) |
                         btCollisionObject::CF_STATIC_OBJECT);
    w.detectCollisions();
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    btVector3 mn, mx;
    w.broadphase().getBroadphaseAabb(mn, mx);
    EXPECT_LE(mn.x(), btScalar(-0.5));
    EXPECT_GE(mx.x(), btScalar(1.4));
}

/// Pairs of leaves that did not move carry over between steps; a pair whose leaf moved is searched again: it goes
/// when the boxes part, comes back when they meet, and the pairs of objects that stay put stay.
TEST(ObjectLevel, PairsFollowMovesAndCarryOverOtherwise) {
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    w.world().setGravity(btVector3(0, 0, 0));
    w.addBody(box, 1, at(0, 0, 0));
    w.addBody(box, 1, at(0.9, 0, 0));
    btRigidBody* mover = w.addBody(box, 1, at(10, 0, 0));
    w.addBody(box, 1, at(10.9, 0, 0));
    auto pairs = [&] { return w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(); };
    for (int step = 0; step < 4; ++step) w.detectCollisions();  // the leaves settle
    EXPECT_EQ(pairs(), 2);
    EXPECT_EQ(w.cullideBroadphase()->getLastFrameStats().carriedPairs, 2u);
    mover->setWorldTransform(at(30, 0, 0));
    w.detectCollisions();
    EXPECT_EQ(pairs(), 1) << "the pair of a leaf that moved away must go";
    mover->setWorldTransform(at(0.5, 0.9, 0));
    w.detectCollisions();
    EXPECT_EQ(pairs(), 3) << "a leaf that moved in must pair with both resting boxes";
}

}  // namespace
}  // namespace cullide::test
