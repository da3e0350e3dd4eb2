// Scene 6: ghost objects (pair callback, private pair cache dispatched through the world's dispatcher, kinematic
// character controller), CULLIDE against Bullet's default pipeline.
#include "SceneSupport.h"

#include <BulletCollision/CollisionDispatch/btGhostObject.h>
#include <BulletDynamics/Character/btKinematicCharacterController.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

namespace cullide::test {
namespace {

/// btGhostPairCallback that also counts the insertions and removals it sees per ghost.
struct CountingGhostCallback : btGhostPairCallback {
    std::map<const btCollisionObject*, long> balance;
    std::size_t added = 0, removed = 0;
    btBroadphasePair* addOverlappingPair(btBroadphaseProxy* p0, btBroadphaseProxy* p1) override {
        count(p0, p1, +1);
        ++added;
        return btGhostPairCallback::addOverlappingPair(p0, p1);
    }
    void* removeOverlappingPair(btBroadphaseProxy* p0, btBroadphaseProxy* p1, btDispatcher* d) override {
        count(p0, p1, -1);
        ++removed;
        return btGhostPairCallback::removeOverlappingPair(p0, p1, d);
    }
    void count(btBroadphaseProxy* p0, btBroadphaseProxy* p1, long delta) {
        for (btBroadphaseProxy* p : {p0, p1}) {
            const auto* o = static_cast<const btCollisionObject*>(p->m_clientObject);
            if (btGhostObject::upcast(o) != nullptr) balance[o] += delta;
        }
    }
};

struct GhostWorld {
    CountingGhostCallback callback;
    btPairCachingGhostObject* ghost = nullptr;
    btBoxShape ghostShape{btVector3(2, btScalar(1.5), 2)};

    void install(TestWorld& w) {
        w.world().getPairCache()->setInternalGhostPairCallback(&callback);
        auto g = std::make_unique<btPairCachingGhostObject>();
        g->setCollisionShape(&ghostShape);
        g->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, 2, 0)));
        g->setCollisionFlags(g->getCollisionFlags() | btCollisionObject::CF_NO_CONTACT_RESPONSE);
        ghost = g.get();
        w.world().addCollisionObject(ghost, btBroadphaseProxy::SensorTrigger,
                                     btBroadphaseProxy::AllFilter & ~btBroadphaseProxy::SensorTrigger);
        w.adopt(std::move(g));
    }
};

std::set<int> ghostOverlaps(const btGhostObject& g) {
    std::set<int> out;
    for (int i = 0; i < g.getNumOverlappingObjects(); ++i) out.insert(g.getOverlappingObject(i)->getUserIndex());
    return out;
}

/// Objects whose broadphase AABB comes within `grow` of the ghost's (what a ghost object reports).
std::set<int> aabbOverlaps(btCollisionWorld& w, const btCollisionObject& g, btScalar grow) {
    std::set<int> out;
    const btBroadphaseProxy* gp = g.getBroadphaseHandle();
    const btVector3 pad(grow, grow, grow);
    for (int i = 0; i < w.getNumCollisionObjects(); ++i) {
        const btCollisionObject* o = w.getCollisionObjectArray()[i];
        const btBroadphaseProxy* p = o->getBroadphaseHandle();
        if (o == &g || !(gp->m_collisionFilterGroup & p->m_collisionFilterMask) ||
            !(p->m_collisionFilterGroup & gp->m_collisionFilterMask))
            continue;
        if (TestAabbAgainstAabb2(gp->m_aabbMin - pad, gp->m_aabbMax + pad, p->m_aabbMin, p->m_aabbMax))
            out.insert(o->getUserIndex());
    }
    return out;
}

/// Objects the ghost actually touches: its private pair cache dispatched through the world's dispatcher (what
/// btKinematicCharacterController does).
std::set<int> ghostTouches(TestWorld& w, btPairCachingGhostObject& g) {
    w.dispatcher().dispatchAllCollisionPairs(g.getOverlappingPairCache(), w.world().getDispatchInfo(),
                                             &w.dispatcher());
    std::set<int> out;
    btBroadphasePairArray& pairs = g.getOverlappingPairCache()->getOverlappingPairArray();
    for (int i = 0; i < pairs.size(); ++i) {
        btManifoldArray manifolds;
        if (pairs[i].m_algorithm != nullptr) pairs[i].m_algorithm->getAllContactManifolds(manifolds);
        for (int m = 0; m < manifolds.size(); ++m)
            for (int c = 0; c < manifolds[m]->getNumContacts(); ++c)
                if (manifolds[m]->getContactPoint(c).getDistance() < 0) {
                    const btCollisionObject* other =
                        manifolds[m]->getBody0() == &g ? manifolds[m]->getBody1() : manifolds[m]->getBody0();
                    out.insert(other->getUserIndex());
                }
    }
    return out;
}

TEST(BulletGhost, PairCallbackPrivateCacheAndRemoval) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(16, 1, btScalar(0.5));
    btCollisionShape* sphere = shapes.sphere(btScalar(0.35));
    btCollisionShape* hull = shapes.hull(btVector3(btScalar(0.4), btScalar(0.4), btScalar(0.4)), 16, 9);
    auto populate = [&](TestWorld& w, GhostWorld& gw) {
        w.addBody(ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 24; ++k)
            w.addBody(k % 2 ? sphere : hull, 1,
                      btTransform(btQuaternion::getIdentity(),
                                  btVector3(btScalar(-2.5 + 0.4 * (k % 12)), btScalar(5 + 1.2 * (k / 12)),
                                            btScalar(0.4 * (k % 5) - 0.8))));
        gw.install(w);
    };
    GhostWorld ga, gb;  // outlive the worlds: their callbacks are installed in the worlds' pair caches
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    populate(reference, ga);
    populate(cullide, gb);
    std::size_t overlapSteps = 0, touchSteps = 0;
    MirrorOptions options;
    options.steps = 150;
    // Hull-landscape manifolds: sorted vs BVH triangle order (see the landscape scene).
    options.tolerance = [](const std::pair<int, int>& pair) {
        return pair.first == 0 ? double(gContactBreakingThreshold) * 1.5 : 1e-6;
    };
    options.each = [&](int step, TestWorld& a, TestWorld& b) {
        // Pairs of the ghost are Bullet's: btDbvtBroadphase's (fattened leaves, lazy removal), a superset of the
        // exact AABB overlaps, the same objects in both worlds.
        const std::set<int> got = ghostOverlaps(*gb.ghost);
        const std::set<int> exact = aabbOverlaps(b.world(), *gb.ghost, 0);
        const std::set<int> dbvt = ghostOverlaps(*ga.ghost);
        ASSERT_EQ(got, dbvt) << "step " << step;
        ASSERT_TRUE(std::includes(got.begin(), got.end(), exact.begin(), exact.end())) << "step " << step;
        ASSERT_EQ(gb.callback.balance[gb.ghost], long(got.size())) << "ghost callback missed an insertion/removal";
        overlapSteps += got.empty() ? 0 : 1;
        // The ghost's private cache through each world's dispatcher: the same objects touch it.
        mirrorState(a, b);
        a.world().updateAabbs();
        b.world().updateAabbs();
        const std::set<int> touchA = ghostTouches(a, *ga.ghost);
        const std::set<int> touchB = ghostTouches(b, *gb.ghost);
        ASSERT_EQ(touchA, touchB) << "step " << step;
        touchSteps += touchB.empty() ? 0 : 1;
        if (step == 100) {
            // Removing objects that overlap the ghost updates its list at once (pair callback on removal).
            for (int i : got) {
                b.world().removeCollisionObject(b.objectByIndex(i));
                a.world().removeCollisionObject(a.objectByIndex(i));
            }
            EXPECT_TRUE(ghostOverlaps(*gb.ghost).empty());
            EXPECT_EQ(gb.callback.balance[gb.ghost], 0);
        }
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("ghost", run);
    std::printf("  ghost: %zu steps with overlaps, %zu steps with touching objects; pair callback saw %zu insertions "
                "and %zu removals (default: %zu / %zu)\n",
                overlapSteps, touchSteps, gb.callback.added, gb.callback.removed, ga.callback.added,
                ga.callback.removed);
    EXPECT_GT(overlapSteps, 20u);
    EXPECT_GT(touchSteps, 10u);
    expectAgreement(run, 1000);
}

TEST(BulletGhost, KinematicCharacterControllerWalksTheSameWay) {
    CULLIDE_BULLET_REQUIRE_GL();
    ShapeStore shapes;
    btCollisionShape* ground = shapes.landscape(24, 1, btScalar(0.8));
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    btCapsuleShape capsule(btScalar(0.3), btScalar(1.0));
    std::vector<btVector3> finalPositions;
    for (PipelineKind kind : {PipelineKind::Default, PipelineKind::Cullide}) {
        btGhostPairCallback ghostCallback;  // outlives the world, whose pair cache calls it
        TestWorld w(kind);
        w.world().getPairCache()->setInternalGhostPairCallback(&ghostCallback);
        w.addBody(ground, 0, btTransform::getIdentity());
        for (int k = 0; k < 6; ++k)  // obstacles on the path
            w.addBody(box, 0, btTransform(btQuaternion::getIdentity(), btVector3(btScalar(1.5 * k - 2), 1, btScalar(2))));
        auto ghost = std::make_unique<btPairCachingGhostObject>();
        ghost->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(-6, 3, 2)));
        ghost->setCollisionShape(&capsule);
        ghost->setCollisionFlags(btCollisionObject::CF_CHARACTER_OBJECT);
        btPairCachingGhostObject* g = ghost.get();
        w.world().addCollisionObject(g, btBroadphaseProxy::CharacterFilter,
                                     btBroadphaseProxy::StaticFilter | btBroadphaseProxy::DefaultFilter);
        w.adopt(std::move(ghost));
        btKinematicCharacterController controller(g, &capsule, btScalar(0.35), btVector3(0, 1, 0));
        w.world().addAction(&controller);
        for (int s = 0; s < 240; ++s) {
            controller.setWalkDirection(btVector3(btScalar(0.05), 0, btScalar(s < 120 ? 0.0 : 0.02)));
            w.step();
        }
        finalPositions.push_back(g->getWorldTransform().getOrigin());
        w.world().removeAction(&controller);
        w.world().removeCollisionObject(g);
    }
    const double deviation = double((finalPositions[0] - finalPositions[1]).length());
    std::printf("[character controller] final position default (%.3f %.3f %.3f), cullide (%.3f %.3f %.3f), "
                "deviation %.2e\n",
                double(finalPositions[0].x()), double(finalPositions[0].y()), double(finalPositions[0].z()),
                double(finalPositions[1].x()), double(finalPositions[1].y()), double(finalPositions[1].z()),
                deviation);
    EXPECT_GT(finalPositions[1].y(), btScalar(-1.5)) << "fell through the landscape";
    EXPECT_LT(deviation, 1e-3);
}

}  // namespace
}  // namespace cullide::test
