// GImpact mesh-mesh pairs through the dispatcher (the GImpact mesh-mesh algorithm): every manifold point is the one
// Bullet's pipeline makes, bit for bit, culled or not, interpenetrating, for compounds and lone mesh parts, and for
// every narrow-phase thread count.
#include "BulletTestWorld.h"
#include "RandomPose.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <initializer_list>
#include <random>
#include <vector>

namespace cullide::test {
namespace {

/// Every manifold point of the world with everything Bullet stores about it that the narrow phase sets.
std::vector<std::vector<btScalar>> manifoldPoints(btCollisionWorld& world) {
    std::vector<std::vector<btScalar>> out;
    btDispatcher* d = world.getDispatcher();
    for (int m = 0; m < d->getNumManifolds(); ++m) {
        const btPersistentManifold* manifold = d->getManifoldByIndexInternal(m);
        const int a = manifold->getBody0()->getUserIndex(), b = manifold->getBody1()->getUserIndex();
        for (int i = 0; i < manifold->getNumContacts(); ++i) {
            const btManifoldPoint& p = manifold->getContactPoint(i);
            out.push_back({btScalar(a), btScalar(b), btScalar(p.m_partId0), btScalar(p.m_index0), btScalar(p.m_partId1),
                           btScalar(p.m_index1), p.m_positionWorldOnA.x(), p.m_positionWorldOnA.y(),
                           p.m_positionWorldOnA.z(), p.m_positionWorldOnB.x(), p.m_positionWorldOnB.y(),
                           p.m_positionWorldOnB.z(), p.m_normalWorldOnB.x(), p.m_normalWorldOnB.y(),
                           p.m_normalWorldOnB.z(), p.m_distance1});
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// Registers GImpact's algorithm, turns gravity off and adds a body per shape at the origin (mass 1), in order.
std::vector<btRigidBody*> addGImpactBodies(TestWorld& x, std::initializer_list<btCollisionShape*> shapes) {
    btGImpactCollisionAlgorithm::registerAlgorithm(&x.dispatcher());
    x.world().setGravity(btVector3(0, 0, 0));
    std::vector<btRigidBody*> bodies;
    for (btCollisionShape* shape : shapes) bodies.push_back(x.addBody(shape, 1, btTransform::getIdentity()));
    return bodies;
}

/// Crossing tori in many poses, Bullet's pipeline beside the CULLIDE pair: every manifold point must be the same,
/// bit for bit. Returns how many pairs went through the dispatcher's path of interest (see the callers).
std::size_t expectBulletsContactsBitForBit(bool gimpactPairCulling) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(2, btScalar(0.5), 32, 12, btScalar(0.01));
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    w.cullideBroadphase()->setGImpactPairCulling(gimpactPairCulling);
    const std::vector<btRigidBody*> bodies[2] = {addGImpactBodies(reference, {torus, torus}),
                                                 addGImpactBodies(w, {torus, torus})};
    std::mt19937 rng(5);
    std::size_t points = 0;
    std::size_t viaPath = 0;
    for (int pose = 0; pose < 24; ++pose) {
        const btTransform t0 = randomPose(rng, 0.3f);
        const btTransform t1 = randomPose(rng, 0.3f);  // two rings of radius 2 around nearly one centre: they cross
        for (int k = 0; k < 2; ++k) {
            bodies[k][0]->setWorldTransform(t0);
            bodies[k][1]->setWorldTransform(t1);
        }
        reference.detectCollisions(0);
        w.detectCollisions(0);
        const auto expected = manifoldPoints(reference.world());
        EXPECT_EQ(manifoldPoints(w.world()), expected) << "pose " << pose;
        points += expected.size();
        const CullideDispatchStats& d = w.cullideDispatcher()->getLastStepStats();
        viaPath += gimpactPairCulling ? d.penetrationPairs : d.fallbackPairs;
    }
    EXPECT_GT(points, 24u);  // contacts in (nearly) every pose
    return viaPath;
}

// The default: GImpact-GImpact pairs are not culled; the dispatcher runs Bullet's pair search and triangle routine
// through LeafPairSearch and triangles mapped once per call.
TEST(GImpactPairs, NotCulledTheyGetBulletsContactsBitForBit) {
    EXPECT_EQ(expectBulletsContactsBitForBit(false), 24u);
}

// With GImpact pair culling on and the deep-penetration fallback on (its default), an interpenetrating pair takes
// the same route.
TEST(GImpactPairs, CulledAndInterpenetratingTheyGetBulletsContactsBitForBit) {
    EXPECT_GT(expectBulletsContactsBitForBit(true), 12u);
}


// GImpact shapes other than btGImpactMeshShape (a btGImpactCompoundShape of boxes; a btGImpactMeshShapePart used on
// its own) against a GImpact mesh: Bullet's own algorithm, the same contacts bit for bit (the dispatcher's mesh-mesh
// path reads mesh parts and must not take them for meshes).
TEST(GImpactPairs, CompoundsAndLonePartsGetBulletsContactsBitForBit) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(2, btScalar(0.5), 32, 12, btScalar(0.01));
    btBoxShape box(btVector3(btScalar(0.6), btScalar(0.2), btScalar(0.4)));
    btGImpactCompoundShape compound;
    for (int k = 0; k < 4; ++k)
        compound.addChildShape(btTransform(btQuaternion(btVector3(0, 1, 0), btScalar(0.4) * btScalar(k)),
                                           btVector3(btScalar(1.6) * btScalar(k % 2), btScalar(0.3) * btScalar(k), 0)),
                               &box);
    compound.updateBound();
    btGImpactMeshShapePart& lonePart = *static_cast<btGImpactMeshShape*>(torus)->getMeshPart(0);
    lonePart.updateBound();
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    const std::vector<btRigidBody*> bodies[2] = {addGImpactBodies(reference, {torus, &compound, &lonePart}),
                                                 addGImpactBodies(w, {torus, &compound, &lonePart})};
    std::mt19937 rng(11);
    std::size_t points = 0;
    for (int pose = 0; pose < 16; ++pose) {
        const btTransform t[3] = {randomPose(rng, 0.3f), randomPose(rng, 0.3f), randomPose(rng, 0.3f)};
        for (int k = 0; k < 2; ++k)
            for (int b = 0; b < 3; ++b) bodies[k][static_cast<std::size_t>(b)]->setWorldTransform(t[b]);
        reference.detectCollisions(0);
        w.detectCollisions(0);
        const auto expected = manifoldPoints(reference.world());
        EXPECT_EQ(manifoldPoints(w.world()), expected) << "pose " << pose;
        points += expected.size();
    }
    EXPECT_GT(points, 16u);
}

// The narrow-phase threads: for 1 to 8 threads, every manifold point is Bullet's bit for bit, with pairs small and
// large (a 8K-triangle pair is cut into search parts), several pairs at once and one alone.
TEST(GImpactPairs, EveryThreadCountGetsBulletsContactsBitForBit) {
    ShapeStore shapes;
    btCollisionShape* fine = shapes.gimpactTorus(2, btScalar(0.5), 128, 32, btScalar(0.01));  // 8,192 triangles
    btCollisionShape* coarse = shapes.gimpactTorus(2, btScalar(0.5), 24, 10, btScalar(0.02));
    TestWorld reference(PipelineKind::Default);
    const std::vector<btRigidBody*> refBodies = addGImpactBodies(reference, {fine, fine, coarse});
    std::mt19937 rng(17);
    std::vector<std::array<btTransform, 3>> poses;
    for (int pose = 0; pose < 10; ++pose)
        poses.push_back({randomPose(rng, 0.3f), randomPose(rng, 0.3f), randomPose(rng, pose < 5 ? 0.3f : 9.0f)});
    std::vector<std::vector<std::vector<btScalar>>> expected;
    for (const auto& pose : poses) {
        for (std::size_t b = 0; b < 3; ++b) refBodies[b]->setWorldTransform(pose[b]);
        reference.detectCollisions(0);
        expected.push_back(manifoldPoints(reference.world()));
    }
    for (unsigned threads : {1u, 2u, 3u, 8u}) {
        TestWorld w(PipelineKind::Cullide, referenceFactory());
        w.cullideDispatcher()->setNarrowPhaseThreads(threads);
        const std::vector<btRigidBody*> bodies = addGImpactBodies(w, {fine, fine, coarse});
        std::size_t threaded = 0, tasks = 0, points = 0;
        for (std::size_t pose = 0; pose < poses.size(); ++pose) {
            for (std::size_t b = 0; b < 3; ++b) bodies[b]->setWorldTransform(poses[pose][b]);
            w.detectCollisions(0);
            ASSERT_EQ(manifoldPoints(w.world()), expected[pose]) << threads << " threads, pose " << pose;
            threaded += w.cullideDispatcher()->getLastStepStats().threadedMeshPairs;
            tasks += w.cullideDispatcher()->getLastStepStats().threadedTasks;
            points += expected[pose].size();
        }
        EXPECT_GT(points, 40u);
        if (threads == 1) {
            EXPECT_EQ(threaded, 0u);  // computed by each pair's algorithm, as before
        } else {
            EXPECT_GE(threaded, 20u);          // every pose's crossing pairs went ahead
            EXPECT_GT(tasks, threaded + 50u);  // and the fine pair's search was cut into parts
        }
    }
}

}  // namespace
}  // namespace cullide::test
