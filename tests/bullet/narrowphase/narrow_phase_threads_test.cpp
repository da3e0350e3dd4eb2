// The narrow-phase threads for Bullet's own algorithms (narrowphase/ThreadedPairs.h): pairs whose algorithm
// touches only its own manifold run on the dispatcher's worker pool, the rest on the calling thread in Bullet's
// order. Guarded here: a pile of boxes, spheres, capsules, cylinders, cones and hulls on a BVH landscape and a
// heightfield moves bit for bit as in Bullet's default pipeline, step after step and for every thread count (the
// solver reads the manifolds in the dispatcher's order, so a manifold made out of order, a point missed or a
// point added twice changes the trajectories); the threads are used; the application's contact callbacks and a
// drawing debug drawer keep every pair on the calling thread. The CPU reference culler is used (no GL needed).
#include "ThreadedWorlds.h"
#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/CollisionDispatch/btBoxBoxCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCompoundCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCompoundCompoundCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexConcaveCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btConvexConvexAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btEmptyCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSphereTriangleCollisionAlgorithm.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/CollisionShapes/btMultiSphereShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/NarrowPhaseCollision/btMinkowskiPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace cullide::test {
namespace {

/// A heightfield of rolling hills (the shape keeps a pointer to the heights).
struct Heightfield {
    static constexpr int kSize = 33;
    std::vector<float> heights;
    std::unique_ptr<btHeightfieldTerrainShape> shape;
    Heightfield() : heights(kSize * kSize) {
        for (int j = 0; j < kSize; ++j)
            for (int i = 0; i < kSize; ++i)
                heights[static_cast<std::size_t>(j * kSize + i)] =
                    float(0.8 * std::sin(0.45 * i) * std::cos(0.35 * j));
        // The float constructor: Bullet's legacy one reads PHY_FLOAT data as btScalar, i.e. as doubles in a
        // double-precision Bullet (past the end of these floats, heights outside the shape's box).
        shape = std::make_unique<btHeightfieldTerrainShape>(kSize, kSize, heights.data(), btScalar(-1), btScalar(1), 1,
                                                             false);
    }
};

/// Drops bodies of `kinds` (in turn) in 3 layers of perRow x perRow over each of the two grounds, `spacing` apart,
/// each turned a little more than the one before.
struct Drop {
    int perRow;
    double spacing, layerHeight, turnStep;

    void populate(TestWorld& w, btCollisionShape* landscape, const Heightfield& field,
                  const std::vector<btCollisionShape*>& kinds) const {
        w.addBody(landscape, 0, at(-6, 0, 0));
        w.addBody(field.shape.get(), 0, at(14, 0, 0));
        const double centre = 0.5 * (perRow - 1);
        int k = 0;
        for (int side = 0; side < 2; ++side)
            for (int layer = 0; layer < 3; ++layer)
                for (int i = 0; i < perRow; ++i)
                    for (int j = 0; j < perRow; ++j, ++k) {
                        const btQuaternion turn(btVector3(0.3f, 1, 0.2f).normalized(), btScalar(turnStep * k));
                        w.addBody(kinds[static_cast<std::size_t>(k) % kinds.size()], 1,
                                  at((side == 0 ? -6.0 : 14.0) + spacing * (i - centre) + 0.1 * layer,
                                     2.5 + layerHeight * layer, spacing * (j - centre), turn));
                    }
    }
};

/// A pile of mixed convex bodies dropped on a BVH landscape (left) and a heightfield (right): convex-convex pairs
/// of every algorithm Bullet's default configuration makes, and convex-mesh pairs of both kinds of ground.
struct PileScene {
    ShapeStore shapes;
    Heightfield field;
    btCollisionShape* landscape = shapes.landscape(24, 1, btScalar(0.8));
    std::unique_ptr<btCylinderShape> cylinder = std::make_unique<btCylinderShape>(btVector3(0.35f, 0.45f, 0.35f));
    std::unique_ptr<btConeShape> cone = std::make_unique<btConeShape>(btScalar(0.4), btScalar(0.9));
    std::vector<btCollisionShape*> kinds{shapes.box(btVector3(0.45f, 0.35f, 0.5f)), shapes.sphere(btScalar(0.4)),
                                         shapes.capsule(btScalar(0.25), btScalar(0.6)),
                                         shapes.hull(btVector3(0.6f, 0.45f, 0.5f), 40, 11), cylinder.get(), cone.get()};

    void populate(TestWorld& w) const { Drop{6, 1.3, 1.2, 0.37}.populate(w, landscape, field, kinds); }
};

std::size_t threadedPairs(TestWorld& w) { return w.cullideDispatcher()->getTotalStats().threadedPairs; }

TEST(NarrowPhaseThreads, PileMovesBitForBitAsInBulletForEveryThreadCount) {
    expectBitForBit(PileScene{}, {1u, 2u, 5u}, kSleepFrom + 150, [](TestWorld& w, unsigned threads) {
        const std::size_t contacts = contactsOf(w.world()).size();
        int asleep = 0;
        for (btCollisionObject* o : w.objects()) asleep += o->getActivationState() == ISLAND_SLEEPING ? 1 : 0;
        std::printf("[ measure  ] %u threads: %zu pair-steps on the workers, %d manifolds, %zu pairs in contact, %d "
                    "bodies asleep\n",
                    threads, threadedPairs(w), w.dispatcher().getNumManifolds(), contacts, asleep);
        EXPECT_GT(contacts, 150u) << "the pile must rest in contact";
        EXPECT_GT(asleep, 20) << "bodies must fall asleep: their pairs are not collided, on any thread";
        if (threads == 1)
            EXPECT_EQ(threadedPairs(w), 0u);
        else
            EXPECT_GT(threadedPairs(w), 20000u) << "most pairs of a resting pile run on the narrow-phase threads";
    });
}

/// Compounds as convex decompositions give them (2-4 hulls) and as furniture is built (boxes and a sphere), dropped
/// on the landscape and the heightfield and on each other: compound-mesh pairs whose children
/// meet triangles and compound-compound pairs (every pair a threadable one could be), children starting and stopping
/// to overlap the other shape as the bodies fall, tumble and settle.
struct CompoundScene {
    ShapeStore shapes;
    Heightfield field;
    btCollisionShape* landscape = shapes.landscape(24, 1, btScalar(0.8));
    std::vector<std::unique_ptr<btCompoundShape>> compounds;
    std::vector<btCollisionShape*> kinds;

    CompoundScene() {
        for (int k = 0; k < 3; ++k) {
            compounds.push_back(std::make_unique<btCompoundShape>());
            const int parts = 2 + k;
            for (int p = 0; p < parts; ++p) {
                const double angle = 6.2832 * p / parts;
                compounds.back()->addChildShape(
                    at(0.35 * std::cos(angle), 0.12 * p, 0.35 * std::sin(angle)),
                    shapes.hull(btVector3(0.35f, 0.3f, 0.3f), 16 + 4 * p, static_cast<std::uint32_t>(7 + 3 * k + p)));
            }
        }
        compounds.push_back(std::make_unique<btCompoundShape>());
        compounds.back()->addChildShape(at(0, 0, 0), shapes.box(btVector3(0.5f, 0.08f, 0.35f)));
        compounds.back()->addChildShape(at(-0.4, -0.3, 0), shapes.box(btVector3(0.06f, 0.25f, 0.06f)));
        compounds.back()->addChildShape(at(0.4, 0.25, 0), shapes.sphere(btScalar(0.2)));
        for (const auto& c : compounds) kinds.push_back(c.get());
    }

    void populate(TestWorld& w) const { Drop{5, 1.4, 1.3, 0.41}.populate(w, landscape, field, kinds); }
};

// A thread count is an application's setting: beyond the bound it throws (as cullide::Settings::threads does) and
// leaves the dispatcher as it was, instead of starting that many threads at the next step.
TEST(NarrowPhaseThreads, TooManyThreadsThrowAndLeaveTheSetting) {
    btDefaultCollisionConfiguration config;
    CullideCollisionDispatcher dispatcher(&config);
    dispatcher.setNarrowPhaseThreads(3);
    for (const unsigned threads : {CullideCollisionDispatcher::kMaxNarrowPhaseThreads + 1, 4294967295u})
        EXPECT_THROW(dispatcher.setNarrowPhaseThreads(threads), std::invalid_argument) << threads;
    EXPECT_EQ(dispatcher.getNarrowPhaseThreads(), 3u);
    dispatcher.setNarrowPhaseThreads(CullideCollisionDispatcher::kMaxNarrowPhaseThreads);  // the bound itself holds
    EXPECT_EQ(dispatcher.getNarrowPhaseThreads(), CullideCollisionDispatcher::kMaxNarrowPhaseThreads);
}

TEST(NarrowPhaseThreads, CompoundsMoveBitForBitAsInBulletForEveryThreadCount) {
    expectBitForBit(CompoundScene{}, {1u, 2u, 5u}, 200, [](TestWorld& w, unsigned threads) {
        std::printf("[ measure  ] %u threads: %zu pair-steps on the workers, %d manifolds, %zu pairs in contact\n",
                    threads, threadedPairs(w), w.dispatcher().getNumManifolds(), contactsOf(w.world()).size());
        EXPECT_GT(contactsOf(w.world()).size(), 100u) << "the bodies must rest in contact";
        if (threads == 1)
            EXPECT_EQ(threadedPairs(w), 0u);
        else
            EXPECT_GT(threadedPairs(w), 10000u) << "compound pairs run on the narrow-phase threads";
    });
}

TEST(NarrowPhaseThreads, CompoundsEditedWhileInContactStayBitForBit) {
    // A compound that gains and loses a child bumps its revision: Bullet's algorithm then remakes its children's
    // algorithms (and manifolds), which only the calling thread may do, in Bullet's order.
    CompoundScene scene;
    SideBySide worlds(scene, 2);
    const std::unique_ptr<TestWorld>& reference = worlds.reference;
    TestWorld& w = worlds.swap;
    EXPECT_EQ(firstDivergingStep(*reference, w, 80), -1);
    btCompoundShape& edited = *scene.compounds[1];  // shared by both worlds: the same edit in each
    btCollisionShape* extra = scene.shapes.box(btVector3(0.2f, 0.2f, 0.2f));
    edited.addChildShape(at(0, -0.25, 0), extra);
    EXPECT_EQ(firstDivergingStep(*reference, w, 20), -1) << "after adding a child";
    edited.removeChildShape(extra);
    EXPECT_EQ(firstDivergingStep(*reference, w, 20), -1) << "after removing it";
    // A child replaced: as many children as the algorithms hold, but a new revision.
    const btTransform place = edited.getChildTransform(0);
    edited.removeChildShapeByIndex(0);
    edited.addChildShape(place, scene.shapes.hull(btVector3(0.3f, 0.35f, 0.3f), 20, 41));
    const std::size_t before = threadedPairs(w);
    EXPECT_EQ(firstDivergingStep(*reference, w, 20), -1) << "after replacing a child";
    EXPECT_GT(threadedPairs(w), before) << "the other compounds' pairs still run on the workers";
}

/// Every thread that ran an application callback.
struct CallbackThreads {
    static std::mutex mutex;
    static std::set<std::thread::id> ids;
    static void record() {
        std::lock_guard<std::mutex> lock(mutex);
        ids.insert(std::this_thread::get_id());
    }
};
std::mutex CallbackThreads::mutex;
std::set<std::thread::id> CallbackThreads::ids;

bool onContactAdded(btManifoldPoint&, const btCollisionObjectWrapper*, int, int, const btCollisionObjectWrapper*, int,
                    int) {
    CallbackThreads::record();
    return false;
}
void onContactStarted(btPersistentManifold* const&) { CallbackThreads::record(); }
bool onContactProcessed(btManifoldPoint&, void*, void*) {
    CallbackThreads::record();
    return false;
}

/// Runs a scene with the narrow-phase threads while an application hook is installed by `install` (and removed by
/// `remove`); returns the swap's dispatch stats over the run (threadedPairs: the pair-steps that ran on the workers).
/// The hook must have run on the calling thread only.
template <typename Scene>
CullideDispatchStats runWithHook(const Scene& scene, const std::function<void(TestWorld&)>& install,
                                 const std::function<void()>& remove, bool expectCalls) {
    SideBySide worlds(scene, 4);
    const std::unique_ptr<TestWorld>& reference = worlds.reference;
    TestWorld& w = worlds.swap;
    install(w);
    CallbackThreads::ids.clear();
    const int diverged = firstDivergingStep(*reference, w, 60);
    remove();
    EXPECT_EQ(diverged, -1);
    if (expectCalls) {
        EXPECT_EQ(CallbackThreads::ids, std::set<std::thread::id>{std::this_thread::get_id()})
            << "the application's callbacks run on the calling thread only";
    }
    return w.cullideDispatcher()->getTotalStats();
}

TEST(NarrowPhaseThreads, ApplicationCallbacksRunOnTheCallingThread) {
    PileScene scene;
    // gContactAddedCallback runs only for objects flagged CF_CUSTOM_MATERIAL_CALLBACK: those pairs stay on the
    // calling thread, the others may run on the workers.
    const std::size_t flagged = runWithHook(
        scene,
        [](TestWorld& w) {
            gContactAddedCallback = onContactAdded;
            for (btCollisionObject* o : w.objects())
                if (o->getUserIndex() % 3 == 0)
                    o->setCollisionFlags(o->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
        },
        [] { gContactAddedCallback = nullptr; }, true).threadedPairs;
    EXPECT_GT(flagged, 1000u) << "pairs of unflagged objects still run on the workers";
    // The manifold callbacks run for every pair: no pair on the workers.
    EXPECT_EQ(runWithHook(
                  scene, [](TestWorld&) { gContactStartedCallback = onContactStarted; },
                  [] { gContactStartedCallback = nullptr; }, true)
                  .threadedPairs,
              0u);
    EXPECT_EQ(runWithHook(
                  scene, [](TestWorld&) { gContactProcessedCallback = onContactProcessed; },
                  [] { gContactProcessedCallback = nullptr; }, true)
                  .threadedPairs,
              0u);
    // The friction combiner is the application's code too.
    static CalculateCombinedCallback saved = nullptr;
    EXPECT_EQ(runWithHook(
                  scene,
                  [](TestWorld&) {
                      saved = gCalculateCombinedFrictionCallback;
                      gCalculateCombinedFrictionCallback = [](const btCollisionObject* a, const btCollisionObject* b) {
                          CallbackThreads::record();
                          return btManifoldResult::calculateCombinedFriction(a, b);
                      };
                  },
                  [] { gCalculateCombinedFrictionCallback = saved; }, true)
                  .threadedPairs,
              0u);
}

/// A debug drawer that draws. Bullet's algorithms may call it while colliding (Debian's 3.24 has the convex-mesh
/// algorithm's triangle drawing compiled out, other builds may not): with one, every pair stays on the calling thread.
class CountingDrawer final : public btIDebugDraw {
public:
    void drawLine(const btVector3&, const btVector3&, const btVector3&) override { CallbackThreads::record(); }
    void drawContactPoint(const btVector3&, const btVector3&, btScalar, int, const btVector3&) override {}
    void reportErrorWarning(const char*) override {}
    void draw3dText(const btVector3&, const char*) override {}
    void setDebugMode(int mode) override { m_mode = mode; }
    int getDebugMode() const override { return m_mode; }

private:
    int m_mode = DBG_DrawWireframe;
};

TEST(NarrowPhaseThreads, DrawingDebugDrawerKeepsPairsOnTheCallingThread) {
    PileScene scene;
    CountingDrawer drawer;
    EXPECT_EQ(runWithHook(
                  scene, [&](TestWorld& w) { w.world().setDebugDrawer(&drawer); }, [] {}, false)
                  .threadedPairs,
              0u);
    drawer.setDebugMode(btIDebugDraw::DBG_NoDebug);  // a drawer that draws nothing keeps the threads
    EXPECT_GT(runWithHook(
                  scene, [&](TestWorld& w) { w.world().setDebugDrawer(&drawer); }, [] {}, false)
                  .threadedPairs,
              1000u);
}

// The rules, one by one: which algorithms, shapes and registrations may run off the calling thread.
TEST(NarrowPhaseThreads, OnlyBulletsOwnAlgorithmsOnBulletsOwnShapesRunOnTheWorkers) {
    ShapeStore shapes;
    btDefaultCollisionConfiguration config;
    btDefaultCollisionConstructionInfo minkowskiInfo;
    minkowskiInfo.m_useEpaPenetrationAlgorithm = false;
    btDefaultCollisionConfiguration minkowski(minkowskiInfo);
    btBoxShape box(btVector3(1, 1, 1));
    btCompoundShape compound;
    compound.addChildShape(btTransform::getIdentity(), &box);
    btCollisionShape* hull = shapes.hull(btVector3(1, 1, 1), 20, 3);
    btCollisionShape* landscape = shapes.landscape(4, 1, 1);
    Heightfield field;
    struct MySphere : btSphereShape {
        MySphere() : btSphereShape(1) {}
    } mySphere;  // an application's shape class: its support function may not be safe to call from two threads
    const auto cf = [](btDefaultCollisionConfiguration& c, const btCollisionShape* a, const btCollisionShape* b) {
        return c.getCollisionAlgorithmCreateFunc(a->getShapeType(), b->getShapeType());
    };
    const auto tri = [](btDefaultCollisionConfiguration& c, const btCollisionShape* a) {
        return c.getCollisionAlgorithmCreateFunc(a->getShapeType(), TRIANGLE_SHAPE_PROXYTYPE);
    };
    using bullet::threadableAlgorithm;
    using K = bullet::AlgorithmKind;
    EXPECT_EQ(bullet::algorithmKindOf(typeid(btConvexConvexAlgorithm)), K::ConvexConvex);
    EXPECT_EQ(bullet::algorithmKindOf(typeid(btBoxBoxCollisionAlgorithm)), K::Convex);
    EXPECT_EQ(bullet::algorithmKindOf(typeid(btConvexConcaveCollisionAlgorithm)), K::ConvexConcave);
    EXPECT_EQ(bullet::algorithmKindOf(typeid(btCompoundCollisionAlgorithm)), K::Compound);
    EXPECT_EQ(bullet::algorithmKindOf(typeid(btCompoundCompoundCollisionAlgorithm)), K::Compound);
    // Convex pairs: Bullet's shapes, Bullet's convex algorithm with GJK-EPA.
    EXPECT_TRUE(threadableAlgorithm(K::ConvexConvex, *hull, box, cf(config, hull, &box), nullptr));
    EXPECT_FALSE(threadableAlgorithm(K::ConvexConvex, *hull, box, cf(minkowski, hull, &box), nullptr))
        << "btMinkowskiPenetrationDepthSolver writes a static table";
    EXPECT_FALSE(threadableAlgorithm(K::ConvexConvex, *hull, mySphere, cf(config, hull, &mySphere), nullptr));
    EXPECT_TRUE(threadableAlgorithm(K::Convex, box, box, cf(config, &box, &box), nullptr));
    EXPECT_FALSE(threadableAlgorithm(K::Other, box, compound, cf(config, &box, &compound), nullptr));
    // Convex against a BVH mesh or a heightfield, either order: each triangle's algorithm is made and freed on the
    // worker, so it must be Bullet's too.
    EXPECT_TRUE(threadableAlgorithm(K::ConvexConcave, *hull, *landscape, cf(config, hull, landscape),
                                    tri(config, hull)));
    EXPECT_TRUE(threadableAlgorithm(K::ConvexConcave, *field.shape, box, cf(config, field.shape.get(), &box),
                                    tri(config, &box)));
    EXPECT_FALSE(threadableAlgorithm(K::ConvexConcave, *hull, *landscape, cf(config, hull, landscape),
                                     tri(minkowski, hull)));
    EXPECT_FALSE(threadableAlgorithm(K::ConvexConcave, compound, *landscape, cf(config, &compound, landscape),
                                     tri(config, &compound)));
    btEmptyAlgorithm::CreateFunc custom;  // an application's registration for convex-triangle pairs
    EXPECT_FALSE(threadableAlgorithm(K::ConvexConcave, *hull, *landscape, cf(config, hull, landscape), &custom));
    // A convex triangle mesh walks its mesh interface's triangles: Bullet's vertex arrays only.
    btCollisionShape* convexMesh = shapes.convexMesh(btVector3(1, 1, 1), 4, 6);
    btCollisionShape* ownConvexMesh = shapes.convexMesh(btVector3(1, 1, 1), 4, 6, true);
    EXPECT_TRUE(threadableAlgorithm(K::ConvexConvex, *convexMesh, box, cf(config, convexMesh, &box), nullptr));
    EXPECT_TRUE(threadableAlgorithm(K::ConvexConcave, *convexMesh, *landscape, cf(config, convexMesh, landscape),
                                    tri(config, convexMesh)));
    EXPECT_FALSE(threadableAlgorithm(K::ConvexConvex, *ownConvexMesh, box, cf(config, ownConvexMesh, &box), nullptr));
}

/// Capsules and spheres on a plane: every pair is one Bullet collides in closed form (capsule-capsule and
/// capsule-sphere inside btConvexConvexAlgorithm, sphere-sphere, convex-plane), cheaper than a hand-off.
struct CapsulePileScene {
    ShapeStore shapes;
    btCollisionShape* plane = shapes.plane(btVector3(0, 1, 0), 0);
    std::vector<btCollisionShape*> kinds{shapes.capsule(btScalar(0.2), btScalar(0.6)), shapes.sphere(btScalar(0.25)),
                                         shapes.capsule(btScalar(0.15), btScalar(0.4))};

    void populate(TestWorld& w) const {
        w.addBody(plane, 0, at(0, 0, 0));
        for (int k = 0; k < 300; ++k) {
            const btQuaternion turn(btVector3(1, 0.3f, 0.2f).normalized(), btScalar(0.7 * k));
            w.addBody(kinds[std::size_t(k) % kinds.size()], 1,
                      at(0.45 * (k % 10 - 4.5), 0.5 + 0.35 * (k / 100), 0.45 * ((k / 10) % 10 - 4.5), turn));
        }
    }
};

TEST(NarrowPhaseThreads, ClosedFormPairsStayOnTheCallingThread) {
    CapsulePileScene scene;
    SideBySide worlds(scene, 2);
    EXPECT_EQ(firstDivergingStep(*worlds.reference, worlds.swap, 120), -1);
    EXPECT_GT(contactsOf(worlds.swap.world()).size(), 300u) << "the capsules must touch each other";
    EXPECT_EQ(threadedPairs(worlds.swap), 0u) << "no capsule or sphere pair is handed to a worker";
}

/// Convex triangle meshes, multi-sphere shapes and hulls dropped on the landscape and the heightfield: GJK pairs
/// whose support functions walk a mesh's triangles or a sphere list.
struct ConvexMeshScene {
    ShapeStore shapes;
    Heightfield field;
    btCollisionShape* landscape = shapes.landscape(24, 1, btScalar(0.8));
    std::unique_ptr<btMultiSphereShape> multiSphere;
    std::vector<btCollisionShape*> kinds;

    ConvexMeshScene() {
        const btVector3 centres[] = {btVector3(-0.3f, 0, 0), btVector3(0.3f, 0.1f, 0), btVector3(0, -0.2f, 0.2f)};
        const btScalar radii[] = {btScalar(0.3), btScalar(0.25), btScalar(0.2)};
        multiSphere = std::make_unique<btMultiSphereShape>(centres, radii, 3);
        kinds = {shapes.convexMesh(btVector3(0.5f, 0.4f, 0.45f), 6, 8), multiSphere.get(),
                 shapes.convexMesh(btVector3(0.35f, 0.5f, 0.35f), 5, 7),
                 shapes.hull(btVector3(0.45f, 0.4f, 0.4f), 30, 9)};
    }

    void populate(TestWorld& w) const { Drop{5, 1.3, 1.2, 0.29}.populate(w, landscape, field, kinds); }
};

TEST(NarrowPhaseThreads, ConvexMeshesAndMultiSpheresMoveBitForBitOnTheWorkers) {
    expectBitForBit(ConvexMeshScene{}, {1u, 2u}, 200, [](TestWorld& w, unsigned threads) {
        EXPECT_GT(contactsOf(w.world()).size(), 100u) << "the bodies must rest in contact";
        if (threads > 1) {
            EXPECT_GT(threadedPairs(w), 10000u) << "their pairs run on the narrow-phase threads";
        }
    });
}

TEST(NarrowPhaseThreads, GImpactConvexPairsStayOnTheCallingThreadForHooks) {
    const GImpactMixScene scene;
    EXPECT_GT(runWithHook(
                  scene, [](TestWorld&) {}, [] {}, false)
                  .threadedConvexPairs,
              100u);
    // A contact-added hook sees each point with its triangle's wrapper, on the calling thread.
    EXPECT_EQ(runWithHook(
                  scene,
                  [](TestWorld& w) {
                      gContactAddedCallback = onContactAdded;
                      for (btCollisionObject* o : w.objects())
                          o->setCollisionFlags(o->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
                  },
                  [] { gContactAddedCallback = nullptr; }, true)
                  .threadedConvexPairs,
              0u);
    EXPECT_EQ(runWithHook(
                  scene, [](TestWorld&) { gContactStartedCallback = onContactStarted; },
                  [] { gContactStartedCallback = nullptr; }, true)
                  .threadedConvexPairs,
              0u);
}

}  // namespace
}  // namespace cullide::test
