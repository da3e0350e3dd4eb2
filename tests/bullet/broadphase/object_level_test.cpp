// The broadphase's object level (issue #12, items 1 and 3): Bullet's own btDbvtBroadphase, so the pair cache is
// exactly Bullet's; the CULLIDE levels only for pairs whose narrow phase reads triangles, and the culler's verdict
// deciding whether those pairs make contacts.
#include "SceneSupport.h"

#include <BulletCollision/BroadphaseCollision/btAxisSweep3.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <gtest/gtest.h>

#include <memory>
#include <set>
#include <stdexcept>
#include <vector>

namespace cullide::test {
namespace {

btTransform at(double x, double y, double z, const btQuaternion& q = btQuaternion::getIdentity()) {
    return btTransform(q, btVector3(btScalar(x), btScalar(y), btScalar(z)));
}

/// Two GImpact tori (radius 2, tube 0.2): the first flat, the second upright with its lowest point dipping into the
/// first's hole, far from its tube. Their boxes overlap, their meshes are apart: the culler proves the pair
/// farther than its margin, so the pair (in the cache, as in Bullet) gets a pruned record and no contact. Moved onto
/// the first's tube (0.002 above it), the pair is kept, with triangles, and touches.
TEST(ObjectLevel, CulledPairIsDecidedByTheCuller) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(2, btScalar(0.2), 32, 8, btScalar(0.01));
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    w.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
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
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    EXPECT_TRUE(contactsOf(w.world()).empty());
    // The narrow phase took the pruned record: no Bullet algorithm ran for the pair.
    const CullideDispatchStats& d = w.cullideDispatcher()->getLastStepStats();
    EXPECT_EQ(d.cullidePairs, 1u);
    EXPECT_EQ(d.clearedPairs, 1u);
    EXPECT_EQ(d.fallbackPairs, 0u);

    // Lowest vertex (2, 0.202, 0), right above the first's top vertex (2, 0.2, 0).
    btTransform near = at(2, 2.2 + 0.202, 0, upright);
    other->setWorldTransform(near);
    w.detectCollisions();
    const CullideFrameStats& t = w.cullideBroadphase()->getLastFrameStats();
    EXPECT_EQ(t.culledPairs, 1u);
    EXPECT_EQ(t.prunedPairs, 0u);
    EXPECT_GT(t.trianglePairs, 0u);
    EXPECT_EQ(w.broadphase().getOverlappingPairCache()->getNumOverlappingPairs(), 1);
    EXPECT_EQ(contactsOf(w.world()).size(), 1u);
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

/// The pair cache is btDbvtBroadphase's, step by step, whatever moves, rests, changes flags or goes: a pair whose
/// leaf moved away goes (lazily, as in Bullet), one that moved in comes, resting pairs stay.
TEST(ObjectLevel, PairCacheIsBulletsStepByStep) {
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    std::vector<btRigidBody*> movers[2];
    int k = 0;
    for (TestWorld* x : {&reference, &w}) {
        x->world().setGravity(btVector3(0, 0, 0));
        for (int i = 0; i < 40; ++i) {
            btRigidBody* b = x->addBody(box, i % 5 == 0 ? 0 : 1, at(0.9 * (i % 8), 0.9 * (i / 8), 0));
            if (i % 7 == 3) movers[k].push_back(b);
        }
        ++k;
    }
    for (int step = 0; step < 30; ++step) {
        for (int side = 0; side < 2; ++side) {
            for (std::size_t m = 0; m < movers[side].size(); ++m) {
                btRigidBody* b = movers[side][m];
                const double x = 0.9 * double((step + 3 * int(m)) % 12) - 2.0;
                b->setWorldTransform(at(x, 0.9 * double(m), 0));
                if (step == 10 + int(m)) b->setCollisionFlags(b->getCollisionFlags() | btCollisionObject::CF_STATIC_OBJECT);
                if (step == 20 + int(m)) b->setCollisionFlags(b->getCollisionFlags() & ~btCollisionObject::CF_STATIC_OBJECT);
            }
        }
        reference.detectCollisions();
        w.detectCollisions();
        ASSERT_EQ(pairsOf(w.world()), pairsOf(reference.world())) << "step " << step;
        ASSERT_GT(pairsOf(w.world()).size(), 10u);
    }
    EXPECT_EQ(w.cullideBroadphase()->getLastFrameStats().culledPairs, 0u) << "boxes: nobody reads their triangles";
}

/// Two GImpact tori pushed into each other: interpenetrating, so Bullet's full algorithm runs the pair (the
/// deep-penetration fallback), and for the next 4 steps the pair skips the culler (nothing it computes would be
/// read), then is culled again. The contacts are Bullet's at every step.
TEST(ObjectLevel, InterpenetratingPairsSkipTheCullerForAFewSteps) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(2, btScalar(0.4), 24, 8, btScalar(0.01));
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    w.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    const btQuaternion upright(btVector3(1, 0, 0), SIMD_HALF_PI);
    for (TestWorld* x : {&reference, &w}) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&x->dispatcher());
        x->world().setGravity(btVector3(0, 0, 0));
        x->addBody(torus, 1, at(0, 0, 0));
        x->addBody(torus, 1, at(0, 0, 0, upright));  // the rings cross at (+-2, 0, 0): the meshes intersect
    }
    std::vector<std::size_t> culled, skipped, penetrating;
    for (int step = 0; step < 7; ++step) {
        reference.detectCollisions();
        w.detectCollisions();
        const CullideFrameStats& s = w.cullideBroadphase()->getLastFrameStats();
        culled.push_back(s.culledPairs);
        skipped.push_back(s.penetratingSkipped);
        penetrating.push_back(s.interpenetratingPairs);
        const ContactMap a = contactsOf(reference.world());
        const ContactMap b = contactsOf(w.world());
        ASSERT_EQ(a.size(), 1u);
        ASSERT_EQ(b.size(), 1u);
        EXPECT_EQ(a.begin()->second.points, b.begin()->second.points) << "step " << step;
        EXPECT_EQ(a.begin()->second.minDistance, b.begin()->second.minDistance) << "step " << step;
        const CullideDispatchStats& d = w.cullideDispatcher()->getLastStepStats();
        EXPECT_EQ(d.cullidePairs + d.fallbackPairs, 1u) << "step " << step;
    }
    EXPECT_EQ(culled, (std::vector<std::size_t>{1, 0, 0, 0, 0, 1, 0}));
    EXPECT_EQ(skipped, (std::vector<std::size_t>{0, 1, 1, 1, 1, 0, 1}));
    EXPECT_EQ(penetrating, (std::vector<std::size_t>{1, 0, 0, 0, 0, 1, 0}));
}

/// A dynamics world over any broadphase: Bullet's btAxisSweep3 or btDbvtBroadphase with Bullet's dispatcher, or the
/// swap with the given object level.
struct AnyWorld {
    btDefaultCollisionConfiguration config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    btSequentialImpulseConstraintSolver solver;
    std::unique_ptr<btDiscreteDynamicsWorld> world;
    std::vector<std::unique_ptr<btRigidBody>> bodies;
    std::vector<std::unique_ptr<btDefaultMotionState>> motion;

    AnyWorld(std::unique_ptr<btBroadphaseInterface> objectLevel, bool swap) {
        if (swap) {
            auto bp = std::make_unique<CullideBroadphase>(Settings{}, nullptr, referenceFactory());
            if (objectLevel) bp->setObjectLevel(std::move(objectLevel));
            dispatcher = std::make_unique<CullideCollisionDispatcher>(&config, bp.get());
            broadphase = std::move(bp);
        } else {
            broadphase = std::move(objectLevel);
            dispatcher = std::make_unique<btCollisionDispatcher>(&config);
        }
        world = std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), broadphase.get(), &solver, &config);
        world->setGravity(btVector3(0, 0, 0));
    }
    ~AnyWorld() {
        for (auto& b : bodies) world->removeRigidBody(b.get());
    }
    btRigidBody* add(btCollisionShape* shape, btScalar mass, const btTransform& t) {
        btVector3 inertia(0, 0, 0);
        if (mass > 0) shape->calculateLocalInertia(mass, inertia);
        motion.push_back(std::make_unique<btDefaultMotionState>(t));
        bodies.push_back(std::make_unique<btRigidBody>(mass, motion.back().get(), shape, inertia));
        bodies.back()->setUserIndex(static_cast<int>(bodies.size() - 1));
        world->addRigidBody(bodies.back().get());
        return bodies.back().get();
    }
};

std::unique_ptr<btBroadphaseInterface> sweep() {
    return std::make_unique<btAxisSweep3>(btVector3(-50, -50, -50), btVector3(50, 50, 50));
}

/// An application that used btAxisSweep3 hands it to the swap (setObjectLevel): the pair cache is btAxisSweep3's,
/// step by step (not btDbvtBroadphase's, which differs here: fattened leaves), ray tests answer as its, contacts are
/// made on its pairs.
TEST(ObjectLevel, AnApplicationsBroadphaseBecomesTheObjectLevel) {
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    AnyWorld sap(sweep(), false), dbvt(std::make_unique<btDbvtBroadphase>(), false), swap(sweep(), true);
    AnyWorld* worlds[] = {&sap, &dbvt, &swap};
    for (AnyWorld* w : worlds)
        for (int i = 0; i < 40; ++i) w->add(box, i % 5 == 0 ? 0 : 1, at(0.9 * (i % 8), 0.9 * (i / 8), 0));
    int dbvtDiffers = 0;
    for (int step = 0; step < 30; ++step) {
        for (AnyWorld* w : worlds) {
            for (std::size_t i = 3; i < w->bodies.size(); i += 7) {  // movers
                const double x = 0.9 * double((step + 3 * int(i)) % 12) - 2.0;
                w->bodies[i]->setWorldTransform(at(x, 0.9 * double(i % 5), 0));
            }
            w->world->performDiscreteCollisionDetection();
        }
        ASSERT_EQ(pairsOf(*swap.world), pairsOf(*sap.world)) << "step " << step;
        EXPECT_EQ(contactsOf(*swap.world).size(), contactsOf(*sap.world).size()) << "step " << step;
        dbvtDiffers += pairsOf(*dbvt.world) != pairsOf(*sap.world) ? 1 : 0;
        btCollisionWorld::AllHitsRayResultCallback want(btVector3(-3, 0.1f, 0.2f), btVector3(9, 3.3f, 0.2f));
        btCollisionWorld::AllHitsRayResultCallback got(want.m_rayFromWorld, want.m_rayToWorld);
        sap.world->rayTest(want.m_rayFromWorld, want.m_rayToWorld, want);
        swap.world->rayTest(got.m_rayFromWorld, got.m_rayToWorld, got);
        EXPECT_EQ(got.m_hitFractions.size(), want.m_hitFractions.size()) << "step " << step;
    }
    EXPECT_GT(dbvtDiffers, 0) << "the scene must tell btAxisSweep3's pairs from btDbvtBroadphase's";
}

TEST(ObjectLevel, SetObjectLevelValidatesItsInput) {
    CullideBroadphase bp(Settings{}, nullptr, referenceFactory());
    EXPECT_THROW(bp.setObjectLevel(nullptr), std::invalid_argument);
    EXPECT_THROW(bp.setObjectLevel(std::make_unique<CullideBroadphase>(Settings{}, nullptr, referenceFactory())),
                 std::invalid_argument);
    bp.setObjectLevel(sweep());  // no proxies yet: fine
    btCollisionObject object;
    btBoxShape shape(btVector3(1, 1, 1));
    object.setCollisionShape(&shape);
    btBroadphaseProxy* proxy = bp.createProxy(btVector3(-1, -1, -1), btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE, &object,
                                              1, -1, nullptr);
    EXPECT_THROW(bp.setObjectLevel(sweep()), std::logic_error);
    bp.destroyProxy(proxy, nullptr);
}

}  // namespace
}  // namespace cullide::test
