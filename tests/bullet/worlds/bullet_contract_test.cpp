// The btBroadphaseInterface / btCollisionDispatcher contract, with the CPU reference culler (no GL needed):
// static-static pairs by the filter, planes, external pair caches, proxy lifetime, non-finite AABBs, precision
// guard, the algorithm pool, custom registrations, and the landscape scene against the default pipeline.
#include "SceneSupport.h"

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btEmptyCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <LinearMath/btPoolAllocator.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace cullide::test {
namespace {

// In a dynamics world, addCollisionObject (like addRigidBody for static bodies) gives StaticFilter and a mask without
// it, so the overlapping static boxes and the plane do not pair: the filter decides, not the static flag
// (worlds/collision_world_test.cpp has the collision world, where they pair). The plane pairs with every
// dynamic object, as its AABB is infinite: the pair cache is exactly btDbvtBroadphase's.
TEST(BulletContract, StaticStaticFilteredPlanesAsInBullet) {
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(btVector3(1, 1, 1));
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), 0);
    btCollisionShape* sphere = shapes.sphere(btScalar(0.5));
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    for (TestWorld* x : {&reference, &w}) {
        for (int k = 0; k < 3; ++k) {
            auto o = std::make_unique<btCollisionObject>();
            o->setCollisionShape(k == 2 ? plane : box);
            o->setWorldTransform(
                btTransform(btQuaternion::getIdentity(), btVector3(btScalar(k == 1 ? 1.5 : 0), 0, 0)));
            btCollisionObject* raw = o.get();
            x->adopt(std::move(o));
            x->world().addCollisionObject(raw);
        }
        x->addBody(sphere, 1, btTransform(btQuaternion::getIdentity(), btVector3(-5, btScalar(0.49), 0)));
        x->addBody(sphere, 1, btTransform(btQuaternion::getIdentity(), btVector3(-5, 30, 0)));
        x->addBody(sphere, 1, btTransform(btQuaternion::getIdentity(), btVector3(-9, -3, 0)));
        x->addBody(sphere, 1, btTransform(btQuaternion::getIdentity(), btVector3(0, btScalar(1.4), 0)));
        x->detectCollisions();
    }
    const std::set<std::pair<int, int>> expected = {{2, 3}, {2, 4}, {2, 5}, {2, 6}, {0, 6}, {1, 6}};
    EXPECT_EQ(pairsOf(w.world()), expected);
    EXPECT_EQ(pairsOf(w.world()), pairsOf(reference.world()));
    const ContactMap contacts = contactsOf(w.world());
    EXPECT_EQ(contacts.count({2, 3}), 1u) << "the sphere resting on the plane touches it";
    EXPECT_EQ(contacts.count({2, 4}), 0u) << "the sphere far above the plane does not";
}

TEST(BulletContract, ExternalPairCacheProxyLifetimeAndQueries) {
    btHashedOverlappingPairCache external;
    btDefaultCollisionConfiguration config;
    {
        CullideBroadphase broadphase(Settings{}, &external, referenceFactory());
        CullideCollisionDispatcher dispatcher(&config, &broadphase);
        EXPECT_EQ(broadphase.getOverlappingPairCache(), &external);
        btVector3 mn, mx;
        broadphase.getBroadphaseAabb(mn, mx);
        EXPECT_EQ(mn, btVector3(0, 0, 0));
        // No collision objects behind these proxies: box proxies, dynamic.
        btBroadphaseProxy* a = broadphase.createProxy(btVector3(0, 0, 0), btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE,
                                                      nullptr, 1, -1, &dispatcher);
        btBroadphaseProxy* b = broadphase.createProxy(btVector3(btScalar(0.5), 0, 0), btVector3(2, 1, 1),
                                                      BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher);
        btBroadphaseProxy* c = broadphase.createProxy(btVector3(5, 5, 5), btVector3(6, 6, 6), BOX_SHAPE_PROXYTYPE,
                                                      nullptr, 1, -1, &dispatcher);
        EXPECT_NE(a->m_uniqueId, b->m_uniqueId);
        broadphase.calculateOverlappingPairs(&dispatcher);
        EXPECT_EQ(external.getNumOverlappingPairs(), 1);
        EXPECT_NE(external.findPair(a, b), nullptr);
        broadphase.getBroadphaseAabb(mn, mx);
        EXPECT_EQ(mn, btVector3(0, 0, 0));
        EXPECT_EQ(mx, btVector3(6, 6, 6));
        btVector3 amin, amax;
        broadphase.getAabb(c, amin, amax);
        EXPECT_EQ(amax, btVector3(6, 6, 6));
        // aabbTest and rayTest through the internal tree.
        struct Collect : btBroadphaseAabbCallback {
            std::set<btBroadphaseProxy*> hits;
            bool process(const btBroadphaseProxy* p) override {
                hits.insert(const_cast<btBroadphaseProxy*>(p));
                return true;
            }
        } collect;
        broadphase.aabbTest(btVector3(4, 4, 4), btVector3(7, 7, 7), collect);
        EXPECT_EQ(collect.hits, std::set<btBroadphaseProxy*>{c});
        // Moving c onto a creates the pairs; moving it away removes them again, lazily, as btDbvtBroadphase does.
        broadphase.setAabb(c, btVector3(btScalar(0.2), 0, 0), btVector3(btScalar(0.8), 1, 1), &dispatcher);
        broadphase.calculateOverlappingPairs(&dispatcher);
        EXPECT_EQ(external.getNumOverlappingPairs(), 3);
        // The same calls on btDbvtBroadphase give the same pairs at every point.
        btDbvtBroadphase twin;
        btBroadphaseProxy* ta = twin.createProxy(btVector3(0, 0, 0), btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE,
                                                 nullptr, 1, -1, &dispatcher);
        btBroadphaseProxy* tb = twin.createProxy(btVector3(btScalar(0.5), 0, 0), btVector3(2, 1, 1),
                                                 BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher);
        btBroadphaseProxy* tc = twin.createProxy(btVector3(btScalar(0.2), 0, 0), btVector3(btScalar(0.8), 1, 1),
                                                 BOX_SHAPE_PROXYTYPE, nullptr, 1, -1, &dispatcher);
        twin.calculateOverlappingPairs(&dispatcher);
        EXPECT_EQ(twin.getOverlappingPairCache()->getNumOverlappingPairs(), 3);
        for (int step = 0; step < 4; ++step) {
            const btScalar x = btScalar(5 + step);
            broadphase.setAabb(c, btVector3(x, 5, 5), btVector3(x + 1, 6, 6), &dispatcher);
            twin.setAabb(tc, btVector3(x, 5, 5), btVector3(x + 1, 6, 6), &dispatcher);
            broadphase.calculateOverlappingPairs(&dispatcher);
            twin.calculateOverlappingPairs(&dispatcher);
            EXPECT_EQ(external.getNumOverlappingPairs(), twin.getOverlappingPairCache()->getNumOverlappingPairs());
        }
        EXPECT_EQ(external.getNumOverlappingPairs(), 1);
        for (btBroadphaseProxy* p : {ta, tb, tc}) twin.destroyProxy(p, &dispatcher);
        // Destroying a proxy removes its pairs at once.
        broadphase.destroyProxy(a, &dispatcher);
        EXPECT_EQ(external.getNumOverlappingPairs(), 0);
        broadphase.printStats();
        broadphase.destroyProxy(b, &dispatcher);
        broadphase.destroyProxy(c, &dispatcher);
        broadphase.resetPool(&dispatcher);
        broadphase.calculateOverlappingPairs(&dispatcher);
        struct NoHit : btBroadphaseRayCallback {
            bool process(const btBroadphaseProxy*) override {
                ADD_FAILURE() << "hit in an empty broadphase";
                return false;
            }
        } ray;
        broadphase.rayTest(btVector3(0, 0, 0), btVector3(1, 1, 1), ray);
    }
    EXPECT_EQ(external.getNumOverlappingPairs(), 0);  // the external cache outlives the broadphase
}

TEST(BulletContract, NonFiniteAabbRejectedOnceOthersUnaffected) {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.box(btVector3(10, 1, 10));
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    auto populate = [&](TestWorld& w) {
        w.addBody(ground, 0, btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)));
        for (int k = 0; k < 6; ++k)
            w.addBody(box, 1, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.3 * k), btScalar(0.5 + 1.1 * k), 0)));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide, referenceFactory());
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the hull-mesh triangle path (off by default)
    populate(reference);
    populate(cullide);
    testing::internal::CaptureStderr();
    // A static object whose transform is NaN: Bullet passes its NaN AABB to createProxy and setAabb unchecked.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    cullide.addBody(box, 0, btTransform(btQuaternion::getIdentity(), btVector3(nan, 0, 0)));
    MirrorOptions options;
    options.steps = 90;
    const MirrorRun run = runMirrored(reference, cullide, options);
    const std::string err = testing::internal::GetCapturedStderr();
    expectAgreement(run, 300);
    EXPECT_NE(err.find("non-finite AABB"), std::string::npos) << err;
    EXPECT_EQ(err.find("non-finite AABB"), err.rfind("non-finite AABB")) << "reported more than once:\n" << err;
    EXPECT_GE(cullide.cullideBroadphase()->getRejectedCount(), 90u);
    EXPECT_EQ(cullide.cullideBroadphase()->getLastFrameStats().rejectedObjects, 1u);
    for (const auto& pair : pairsOf(cullide.world())) {
        EXPECT_NE(pair.second, 7);
    }
    // Fixing the transform brings the object back: moved into the stack, it pairs with the boxes around it.
    btCollisionObject* fixedObject = cullide.objectByIndex(7);
    fixedObject->setWorldTransform(cullide.objectByIndex(3)->getWorldTransform());
    cullide.detectCollisions();
    int pairsOfFixed = 0;
    for (const auto& pair : pairsOf(cullide.world())) pairsOfFixed += pair.second == 7 ? 1 : 0;
    EXPECT_GE(pairsOfFixed, 2);
}

// A convex hull with a NaN or a huge point (its box still finite: Bullet's support mapping skips the NaN) has no
// triangles for the culler: btConvexHullComputer, which builds them, crashes on a NaN. Its pairs are not culled and
// run Bullet's own algorithm, so the world moves as Bullet's, bit for bit — with every culling switch on, the hull
// alone and as a compound's child, on a BVH mesh and on a GImpact mesh.
TEST(BulletContract, HullsWithUnusablePointsRunBulletsAlgorithms) {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(8, btScalar(1), btScalar(0.2));
    btCollisionShape* gimpactGround = shapes.gimpactTorus(btScalar(3), btScalar(0.8), 24, 12, btScalar(0.04));
    std::vector<std::unique_ptr<btCollisionShape>> own;
    const auto badHull = [&](btScalar bad) {
        auto hull = std::make_unique<btConvexHullShape>();
        for (int i = 0; i < 10; ++i)
            hull->addPoint(btVector3(btScalar(std::cos(1.1 * i)), btScalar(std::sin(0.7 * i)), btScalar(std::cos(2.3 * i))) *
                               btScalar(0.4),
                           false);
        hull->addPoint(btVector3(bad, btScalar(0.1), btScalar(0.1)), false);
        hull->recalcLocalAabb();
        own.push_back(std::move(hull));
        return static_cast<btConvexHullShape*>(own.back().get());
    };
    btConvexHullShape* nanHull = badHull(std::numeric_limits<btScalar>::quiet_NaN());
    btConvexHullShape* hugeHull = badHull(btScalar(1e30));
    auto compound = std::make_unique<btCompoundShape>();
    compound->addChildShape(btTransform::getIdentity(), nanHull);
    const auto populate = [&](TestWorld& w) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(ground, 0, btTransform(btQuaternion::getIdentity(), btVector3(-4, 0, -4)));
        w.addBody(gimpactGround, 0, btTransform(btQuaternion(btVector3(1, 0, 0), SIMD_HALF_PI), btVector3(10, 0, 0)));
        for (int k = 0; k < 2; ++k) {
            const btScalar x = btScalar(10 * k);
            btCollisionShape* bad = k == 0 ? static_cast<btCollisionShape*>(nanHull) : hugeHull;
            w.addBody(bad, 1, btTransform(btQuaternion::getIdentity(), btVector3(x, btScalar(1.2), btScalar(0.3))));
            w.addBody(compound.get(), 1, btTransform(btQuaternion::getIdentity(), btVector3(x, btScalar(1.2), 2)));
        }
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld swap(PipelineKind::Cullide, referenceFactory());
    CullideBroadphase& broadphase = *swap.cullideBroadphase();
    broadphase.setConvexMeshCulling(true);
    broadphase.setGImpactConvexCulling(true);
    broadphase.setGImpactMeshCulling(true);
    broadphase.setGImpactPairCulling(true);
    populate(reference);
    populate(swap);
    int differing = -1;
    std::size_t culled = 0;  // pairs of the bad hulls with the grounds that went through a culling frame
    for (int step = 0; step < 60; ++step) {
        if (firstDifferingStep(reference, swap, 1) >= 0 && differing < 0) differing = step;
        culled += broadphase.getLastFrameStats().culledPairs;
    }
    EXPECT_EQ(differing, -1);
    EXPECT_GT(culled, 0u) << "the culler must see the hulls (before the fix, its frame crashed on the NaN)";
}

TEST(BulletContract, PrecisionGuardAndAlgorithmPool) {
    EXPECT_EQ(detail::bulletScalarSizeOfLibrary(), int(sizeof(btScalar)));
    EXPECT_NO_THROW(detail::requireMatchingBulletPrecision());
    btDefaultCollisionConfiguration config;
    CullideCollisionDispatcher dispatcher(&config);
    btPoolAllocator* pool = config.getCollisionAlgorithmPool();
    void* big = dispatcher.allocateCollisionAlgorithm(pool->getElementSize() + 64);
    EXPECT_FALSE(pool->validPtr(big)) << "an oversized algorithm must not come from the pool";
    dispatcher.freeCollisionAlgorithm(big);
    void* small = dispatcher.allocateCollisionAlgorithm(64);
    EXPECT_TRUE(pool->validPtr(small));
    dispatcher.freeCollisionAlgorithm(small);
}

/// CULLIDE's own algorithms fit Bullet's pool (they are as large as the Bullet classes they extend) and replace
/// only Bullet's own registrations.
TEST(BulletContract, AlgorithmsFitThePoolAndCustomRegistrationsWin) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 16, 8, btScalar(0.04));
    btCollisionShape* ground = shapes.landscape(8, 1, btScalar(0.3));
    btCollisionShape* hull = shapes.hull(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)), 16, 4);
    btEmptyAlgorithm::CreateFunc empty;  // registered below; outlives the world
    TestWorld w(PipelineKind::Cullide, referenceFactory());
    w.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    w.cullideBroadphase()->setConvexMeshCulling(true);  // hull-ground through CULLIDE too
    btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
    w.addBody(ground, 0, btTransform::getIdentity());
    w.addBody(torus, 1, btTransform(btQuaternion::getIdentity(), btVector3(0, 3, 0)));
    w.addBody(torus, 1, btTransform(btQuaternion(btVector3(1, 0, 0), SIMD_HALF_PI), btVector3(btScalar(1.6), 3, 0)));
    w.addBody(hull, 1, btTransform(btQuaternion::getIdentity(), btVector3(-2, 0, 2)));  // cut by the ground
    w.detectCollisions();
    EXPECT_GE(w.cullideDispatcher()->getLastStepStats().cullidePairs, 2u);  // torus-torus and hull-ground
    btPoolAllocator* pool = static_cast<btDefaultCollisionConfiguration&>(
                                *w.dispatcher().getCollisionConfiguration()).getCollisionAlgorithmPool();
    btOverlappingPairCache* cache = w.world().getPairCache();
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        btCollisionAlgorithm* algorithm = cache->getOverlappingPairArrayPtr()[i].m_algorithm;
        if (algorithm != nullptr) {
            EXPECT_TRUE(pool->validPtr(algorithm));
        }
    }
    // A custom (GIMPACT, GIMPACT) registration is respected: CULLIDE does not replace it.
    w.dispatcher().registerCollisionCreateFunc(GIMPACT_SHAPE_PROXYTYPE, GIMPACT_SHAPE_PROXYTYPE, &empty);
    btCollisionObject* second = w.objectByIndex(2);
    w.world().removeCollisionObject(second);
    w.world().addCollisionObject(second);
    w.detectCollisions();
    EXPECT_EQ(contactsOf(w.world()).count({1, 2}), 0u);
}

// The culler is made when a step first has pairs for it: a world without any (the default, no culling switch on)
// never opens a GL context or starts the culler's threads. Settings that demand GPU levels make it at construction,
// where a missing device throws; a factory failing later is reported once and its pairs get Bullet's algorithms.
TEST(BulletContract, CullerMadeWhenFirstNeededAndFactoryErrorsPropagate) {
    int calls = 0;
    const CullideBroadphase::CullerFactory failing = [&calls](const Settings&) -> std::unique_ptr<Culler> {
        ++calls;
        throw GlUnavailableError("no EGL device (test)");
    };
    Settings demanding;
    demanding.gpuLevels = GpuLevels::Always;
    EXPECT_THROW(CullideBroadphase(demanding, nullptr, failing), GlUnavailableError);
    EXPECT_EQ(calls, 1);
    Settings invalid;
    invalid.resolution = 3;
    EXPECT_THROW(CullideBroadphase(invalid, nullptr, referenceFactory()), std::invalid_argument);

    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(8, btScalar(1), btScalar(0.2));
    btCollisionShape* hull = shapes.hull(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35)), 20, 3);
    const auto populate = [&](TestWorld& w) {
        w.addBody(ground, 0, btTransform(btQuaternion::getIdentity(), btVector3(-4, 0, -4)));
        for (int k = 0; k < 4; ++k)
            w.addBody(hull, 1, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(k), btScalar(0.8), 0)));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld swap(PipelineKind::Cullide, failing);
    EXPECT_EQ(calls, 1) << "no culler is made at construction";
    populate(reference);
    populate(swap);
    EXPECT_EQ(firstDifferingStep(reference, swap, 20), -1);
    EXPECT_EQ(calls, 1) << "no culler is made while no pair goes through it (no culling switch on)";
    EXPECT_EQ(swap.cullideBroadphase()->getCullingMargin(), 0.0);
    // Hull-mesh pairs through the culler from now on: the factory is called at the next step and fails; the failure
    // is reported once, the pairs get Bullet's algorithms (bit for bit), and the factory is not called again.
    swap.cullideBroadphase()->setConvexMeshCulling(true);
    testing::internal::CaptureStderr();
    EXPECT_EQ(firstDifferingStep(reference, swap, 20), -1);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(calls, 2);
    EXPECT_NE(err.find("no EGL device (test)"), std::string::npos) << err;
    EXPECT_EQ(err.find("the culler failed"), err.rfind("the culler failed")) << "reported more than once:\n" << err;
    EXPECT_GT(swap.cullideBroadphase()->getLastFrameStats().culledPairs, 0u);
    int points = 0;
    for (int i = 0; i < swap.dispatcher().getNumManifolds(); ++i)
        points += swap.dispatcher().getManifoldByIndexInternal(i)->getNumContacts();
    EXPECT_GT(points, 0) << "the hulls rest on the mesh";
}

/// Three GImpact tori (margin `margin`) falling on a plane, for the culler-recreation tests.
void populateTori(TestWorld& w, ShapeStore& shapes, btScalar margin) {
    btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
    w.addBody(shapes.plane(btVector3(0, 1, 0), 0), 0, btTransform::getIdentity());
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 16, 8, margin);
    for (int k = 0; k < 3; ++k)
        w.addBody(torus, 1, btTransform(btQuaternion(btVector3(1, 0, 0), btScalar(0.4 * k)),
                                        btVector3(btScalar(0.3 * k), btScalar(1 + 1.2 * k), 0)));
}

/// When the culler cannot be recreated with the margin a new shape needs, frames fall back to AABB pairs (and the
/// dispatcher to Bullet's full algorithms): contacts stay right.
/// A proxy created with a non-finite AABB and never updated (a static object whose world never updates static
/// AABBs) is parked: the object level's tree keeps finite volumes, so proxies created and moved later still find
/// each other; the parked proxy gets no pair until it gets a finite box, then pairs as any other.
TEST(BulletContract, NonFiniteProxyNeverHidesOthers) {
    btDefaultCollisionConfiguration config;
    CullideBroadphase broadphase(Settings{}, nullptr, referenceFactory());
    CullideCollisionDispatcher dispatcher(&config, &broadphase);
    const btScalar nan = std::numeric_limits<btScalar>::quiet_NaN();
    std::vector<btBroadphaseProxy*> proxies;
    testing::internal::CaptureStderr();
    for (int k = 0; k < 8; ++k) {
        const btVector3 lo(btScalar(3 * k), 0, 0);
        proxies.push_back(broadphase.createProxy(lo, lo + btVector3(1, 1, 1), BOX_SHAPE_PROXYTYPE, nullptr, 1, -1,
                                                 &dispatcher));
        if (k == 3)
            proxies.push_back(broadphase.createProxy(btVector3(nan, 0, 0), btVector3(nan, 1, 1), BOX_SHAPE_PROXYTYPE,
                                                     nullptr, 1, -1, &dispatcher));
    }
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("non-finite AABB"), std::string::npos) << err;
    btBroadphaseProxy* parked = proxies[4];
    broadphase.calculateOverlappingPairs(&dispatcher);
    EXPECT_EQ(broadphase.getOverlappingPairCache()->getNumOverlappingPairs(), 0);
    // Each box moves onto its right neighbour's place, half overlapping it: 7 pairs among the 8 valid boxes.
    for (std::size_t i = 0; i < proxies.size(); ++i) {
        if (proxies[i] == parked) continue;
        btVector3 lo, hi;
        broadphase.getAabb(proxies[i], lo, hi);
        broadphase.setAabb(proxies[i], lo + btVector3(btScalar(1.5), 0, 0), hi + btVector3(btScalar(1.5), 0, 0),
                           &dispatcher);
        broadphase.setAabb(proxies[i], lo - btVector3(btScalar(1.5), 0, 0), hi - btVector3(btScalar(1.5), 0, 0),
                           &dispatcher);
        broadphase.setAabb(proxies[i], lo, hi + btVector3(btScalar(2.5), 0, 0), &dispatcher);
    }
    broadphase.calculateOverlappingPairs(&dispatcher);
    btOverlappingPairCache* cache = broadphase.getOverlappingPairCache();
    EXPECT_EQ(cache->getNumOverlappingPairs(), 7);
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        const btBroadphasePair& pair = cache->getOverlappingPairArrayPtr()[i];
        EXPECT_NE(pair.m_pProxy0, parked);
        EXPECT_NE(pair.m_pProxy1, parked);
    }
    EXPECT_EQ(broadphase.getLastFrameStats().rejectedObjects, 1u);
    EXPECT_EQ(parked->m_collisionFilterMask, -1) << "parking leaves the application's filter mask alone";
    // A finite box brings it back, with its own filter mask.
    broadphase.setAabb(parked, btVector3(btScalar(0.5), 0, 0), btVector3(btScalar(1.5), 1, 1), &dispatcher);
    broadphase.calculateOverlappingPairs(&dispatcher);
    EXPECT_EQ(parked->m_collisionFilterMask, -1);
    EXPECT_EQ(broadphase.getLastFrameStats().rejectedObjects, 0u);
    EXPECT_NE(cache->findPair(parked, proxies[0]), nullptr);
    EXPECT_EQ(broadphase.getRejectedCount(), 1u);
    for (btBroadphaseProxy* p : proxies) broadphase.destroyProxy(p, &dispatcher);
}

// Parked proxies (non-finite boxes) wait at far points of their own: they meet no valid object and no other parked
// proxy, whatever their filters, and the filter mask stays the application's: one it writes while the object is
// parked holds when the object comes back (an outside probe found it overwritten by the mask the object had when
// parked). Bullet's own tree, with the NaN box in it, keeps or drops the object's old pairs erratically; the swap
// drops them when it parks the object (documented), so only the mask's effect is compared here.
TEST(BulletContract, ParkedObjectsKeepTheApplicationsFilterMask) {
    ShapeStore shapes;
    btCollisionShape* box = shapes.box(btVector3(1, 1, 1));
    CollisionOnlyWorld reference(PipelineKind::Default), cullide(PipelineKind::Cullide);
    const btScalar nan = std::numeric_limits<btScalar>::quiet_NaN();
    testing::internal::CaptureStderr();
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        for (int k = 0; k < 4; ++k)
            w->add(box, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.5 * k), 0, 0)),
                   btBroadphaseProxy::DefaultFilter, btBroadphaseProxy::AllFilter);  // static: the world sets a NaN box
        w->world().performDiscreteCollisionDetection();
        // Objects 0 and 1 go NaN; while they are, the application makes object 0 collide with nothing.
        for (int k = 0; k < 2; ++k)
            w->object(std::size_t(k)).setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(nan, 0, 0)));
        w->world().performDiscreteCollisionDetection();
    }
    const btOverlappingPairCache& parkedCache = *cullide.world().getBroadphase()->getOverlappingPairCache();
    for (int i = 0; i < parkedCache.getNumOverlappingPairs(); ++i) {
        const btBroadphasePair& pair = parkedCache.getOverlappingPairArrayPtr()[i];
        for (const btBroadphaseProxy* p : {pair.m_pProxy0, pair.m_pProxy1})
            EXPECT_GE(static_cast<const btCollisionObject*>(p->m_clientObject)->getUserIndex(), 2)
                << "a parked object has a pair (with a valid one or with the other parked one)";
    }
    for (CollisionOnlyWorld* w : {&reference, &cullide}) {
        w->object(0).getBroadphaseHandle()->m_collisionFilterMask = 0;
        for (int k = 0; k < 2; ++k)
            w->object(std::size_t(k))
                .setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.5 * k), 0, 0)));
        for (int step = 0; step < 3; ++step) w->world().performDiscreteCollisionDetection();
    }
    testing::internal::GetCapturedStderr();
    EXPECT_EQ(cullide.object(0).getBroadphaseHandle()->m_collisionFilterMask, 0);
    EXPECT_EQ(cullide.object(1).getBroadphaseHandle()->m_collisionFilterMask, btBroadphaseProxy::AllFilter);
    const std::set<std::pair<int, int>> expected{{1, 2}, {1, 3}, {2, 3}};  // object 0 collides with nothing
    EXPECT_EQ(pairsOf(cullide.world()), expected);
    EXPECT_EQ(reference.object(0).getBroadphaseHandle()->m_collisionFilterMask, 0);
}

/// A torus whose margin 0.2 needs d > 0.23 against a torus of margin 0.01 (in each world, the same shape) at (x, y, 0), its box overlapping a torus
/// of populateTori's, and its object index.
int addWideTorus(TestWorld& w, btCollisionShape* wide, double x, double y) {
    const int index = w.nextIndex();
    w.addBody(wide, 1, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(x), btScalar(y), 0)));
    return index;
}

/// A torus with a wider margin joins at step 10: the culler made at the first step has too small a margin and
/// cannot be remade; frames fall back to AABB pairs (and the dispatcher to Bullet's full algorithms), contacts right.
TEST(BulletContract, CullerRecreationFailureFallsBackToAabbPairs) {
    ShapeStore shapes;
    int calls = 0;
    const CullideBroadphase::CullerFactory onlyOnce = [&calls](const Settings& s) {
        if (++calls > 1) throw GlUnavailableError("EGL context lost (test)");
        return createReferenceCuller(s);
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide, onlyOnce);
    cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
    populateTori(reference, shapes, btScalar(0.01));  // needs d 0.022
    populateTori(cullide, shapes, btScalar(0.01));
    btCollisionShape* wide = shapes.gimpactTorus(1, btScalar(0.3), 16, 8, btScalar(0.2));
    testing::internal::CaptureStderr();
    MirrorOptions options;
    options.steps = 60;
    options.before = [&](int step, TestWorld& a, TestWorld& b) {
        if (step != 10) return;
        addWideTorus(a, wide, 0, 4.5);  // onto the top torus
        addWideTorus(b, wide, 0, 4.5);
    };
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 ? 1e-6 : 2.0 * double(gContactBreakingThreshold);
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("EGL context lost (test)"), std::string::npos) << err;
    expectAgreement(run, 50);
    EXPECT_GE(calls, 2);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u) << "the first culler's triangles, before the wide torus";
    EXPECT_GT(run.fallbackPairs, 0u);
    EXPECT_LT(cullide.cullideBroadphase()->getCullingMargin(), 0.4);
}

/// The wide torus leaves at step 30: the margin the scene needs drops below half the culler's, so the culler is
/// remade smaller. When that fails (the factory throws or returns nothing), the larger culler is still sound and
/// stays in use: no AABB fallback, no crash on later frames, no retry every frame, contacts right.
TEST(BulletContract, CullerShrinkFailureKeepsTheSoundCuller) {
    for (bool returnNothing : {false, true}) {
        ShapeStore shapes;
        int calls = 0;
        const CullideBroadphase::CullerFactory onlyOnce = [&](const Settings& s) -> std::unique_ptr<Culler> {
            if (++calls == 1) return createReferenceCuller(s);
            if (returnNothing) return nullptr;
            throw GlUnavailableError("EGL context lost (test)");
        };
        TestWorld reference(PipelineKind::Default);
        TestWorld cullide(PipelineKind::Cullide, onlyOnce);
        cullide.cullideBroadphase()->setGImpactPairCulling(true);  // the culled GImpact-GImpact path
        btCollisionShape* wide = shapes.gimpactTorus(1, btScalar(0.3), 16, 8, btScalar(0.2));
        int wideIndex = -1;
        for (TestWorld* w : {&reference, &cullide}) {
            populateTori(*w, shapes, btScalar(0.01));  // needs d 0.022
            wideIndex = addWideTorus(*w, wide, 2.5, 1);  // beside the lowest torus from the first step
        }
        testing::internal::CaptureStderr();
        MirrorOptions options;
        options.steps = 90;
        options.before = [&](int step, TestWorld& a, TestWorld& b) {
            if (step != 30) return;
            for (TestWorld* w : {&a, &b}) w->removeBody(btRigidBody::upcast(w->objectByIndex(wideIndex)));
        };
        options.tolerance = [](const std::pair<int, int>& pair) {
            return pair.first == 0 ? 1e-6 : 2.0 * double(gContactBreakingThreshold);
        };
        const MirrorRun run = runMirrored(reference, cullide, options);
        testing::internal::GetCapturedStderr();
        EXPECT_EQ(calls, 2) << "one failed attempt to shrink, not one per frame";
        EXPECT_GT(cullide.cullideBroadphase()->getCullingMargin(), 0.2);  // the wide torus's pair: 1.1 (0.2 + 0.01)
        expectAgreement(run, 40);
        EXPECT_GT(run.cullidePairsFromTriangles, 0u) << "the culler's triangle lists must still be used";
    }
}

/// The landscape scene with the CPU reference culler: the adapter's logic without GL.
TEST(BulletContract, LandscapeWithReferenceCuller) {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(32, 1, btScalar(1.2));
    btCollisionShape* kinds[] = {shapes.box(btVector3(btScalar(0.5), btScalar(0.4), btScalar(0.6))),
                                 shapes.sphere(btScalar(0.5)), shapes.capsule(btScalar(0.3), btScalar(0.8)),
                                 shapes.hull(btVector3(btScalar(0.7), btScalar(0.5), btScalar(0.6)), 24, 7)};
    auto populate = [&](TestWorld& w) {
        w.addBody(ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 16; ++k)
            w.addBody(kinds[k % 4], 1,
                      btTransform(btQuaternion(btScalar(0.3 * k), 0, 0),
                                  btVector3(btScalar(6 * (k % 4) - 9), btScalar(3), btScalar(6 * (k / 4) - 9))));
    };
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide, referenceFactory());
    cullide.cullideBroadphase()->setConvexMeshCulling(true);  // the hull-mesh triangle path (off by default)
    populate(reference);
    populate(cullide);
    MirrorOptions options;
    options.steps = 150;
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 && pair.second % 4 == 0 ? double(gContactBreakingThreshold) : 1e-6;
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("landscape, reference culler", run);
    expectAgreement(run, 1000);
    EXPECT_GT(run.cullidePairsFromTriangles, 0u);
}

}  // namespace
}  // namespace cullide::test
