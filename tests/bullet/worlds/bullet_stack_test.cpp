// Scene 3: a box stack (pyramid) on a static box ground, and objects added and removed during the simulation,
// both between steps and in the middle of a step (inside solveConstraints, as fracture code does).
#include "SceneSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace cullide::test {
namespace {

struct StackScene {
    ShapeStore shapes;
    btCollisionShape* ground = nullptr;
    btCollisionShape* box = nullptr;
    int rows = 6;

    StackScene() {
        ground = shapes.box(btVector3(20, 1, 20));
        box = shapes.box(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5)));
    }

    void populate(TestWorld& w) const {
        w.addBody(ground, 0, btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)));
        for (int r = 0; r < rows; ++r)
            for (int c = 0; c < rows - r; ++c) {
                const btScalar x = btScalar(c) * btScalar(1.02) - btScalar(rows - r - 1) * btScalar(0.51);
                w.addBody(box, 1, btTransform(btQuaternion::getIdentity(), btVector3(x, btScalar(0.5 + r), 0)));
            }
    }
};

TEST(BulletStack, NoContactMissingAndContactsExact) {
    CULLIDE_BULLET_REQUIRE_GL();
    StackScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(cullide);
    MirrorOptions options;
    options.steps = 180;
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("box stack", run);
    expectAgreement(run, 2000);
}

TEST(BulletStack, StackStandsInBothPipelines) {
    CULLIDE_BULLET_REQUIRE_GL();
    StackScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(cullide);
    for (int s = 0; s < 300; ++s) {
        reference.step();
        cullide.step();
    }
    double maxDeviation = 0.0, maxDrift = 0.0;
    for (std::size_t i = 1; i < reference.objects().size(); ++i) {
        const btVector3 a = reference.objects()[i]->getWorldTransform().getOrigin();
        const btVector3 b = cullide.objects()[i]->getWorldTransform().getOrigin();
        maxDeviation = std::max(maxDeviation, double((a - b).length()));
        // Boxes rest in layers at y = 0.5, 1.5, ...: distance from the nearest layer.
        maxDrift = std::max(maxDrift, std::fabs(double(b.y()) - 0.5 - std::round(double(b.y()) - 0.5)));
    }
    std::printf("[box stack trajectories] after 300 steps: max deviation between pipelines %.3e, max vertical "
                "offset from the resting layer %.3e\n",
                maxDeviation, maxDrift);
    // One island in both pipelines; the solver sees the manifolds in creation order, which differs (pairs are
    // created in a different order): float-level differences, no visible motion.
    EXPECT_LT(maxDeviation, 5e-3);
    EXPECT_LT(maxDrift, 0.05);
}

/// Both worlds get the same additions and removals between steps; contacts must keep agreeing.
TEST(BulletStack, AddAndRemoveBetweenStepsMirrored) {
    CULLIDE_BULLET_REQUIRE_GL();
    StackScene scene;
    scene.rows = 3;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(cullide);
    btCollisionShape* sphere = scene.shapes.sphere(btScalar(0.4));
    MirrorOptions options;
    options.steps = 200;
    options.before = [&](int step, TestWorld& a, TestWorld& b) {
        if (step % 20 == 5 && step < 150) {  // drop a sphere and a box
            for (TestWorld* w : {&a, &b}) {
                const btScalar x = btScalar(-3 + (step / 20) % 7);
                w->addBody(sphere, 1, btTransform(btQuaternion::getIdentity(), btVector3(x, 4, 1)));
                w->addBody(scene.box, 1, btTransform(btQuaternion::getIdentity(), btVector3(x, 5, -1)));
            }
        }
        if (step == 60 || step == 120) {  // remove a resting box of the stack and the oldest dropped sphere
            for (TestWorld* w : {&a, &b}) {
                const int stackBox = step == 60 ? 1 : 4;
                const int dropped = 7 + (step == 60 ? 0 : 2);
                w->removeBody(btRigidBody::upcast(w->objectByIndex(stackBox)));
                w->removeBody(btRigidBody::upcast(w->objectByIndex(dropped)));
            }
        }
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("add/remove between steps", run);
    expectAgreement(run, 500);
}

/// Bodies removed and added inside solveConstraints (the middle of a step). The CULLIDE world must stay
/// consistent: no pair refers to a removed object, added bodies get pairs and land, nothing crashes.
TEST(BulletStack, AddAndRemoveMidStep) {
    CULLIDE_BULLET_REQUIRE_GL();
    StackScene scene;
    scene.rows = 4;
    btCollisionShape* sphere = scene.shapes.sphere(btScalar(0.4));
    for (PipelineKind kind : {PipelineKind::Default, PipelineKind::Cullide}) {
        TestWorld w(kind);
        scene.populate(w);
        int stepNo = 0;
        std::vector<btRigidBody*> removed;
        w.midStep = [&](TestWorld& world) {
            ++stepNo;
            if (stepNo % 15 == 0 && stepNo <= 150) {
                // Remove the highest live box that has contacts right now (its pairs and algorithms go mid-step)...
                for (int i = 10; i >= 1; --i) {  // the original stack boxes
                    auto* body = btRigidBody::upcast(world.objectByIndex(i));
                    if (body == nullptr || !body->isInWorld()) continue;
                    world.removeBody(body);
                    removed.push_back(body);
                    break;
                }
                // ... and add two bodies (a sphere onto the stack area, a box beside it).
                const btScalar x = btScalar(-2 + (stepNo / 15) % 5);
                world.addBody(sphere, 1, btTransform(btQuaternion::getIdentity(), btVector3(x, 6, 0)));
                world.addBody(scene.box, 1, btTransform(btQuaternion::getIdentity(), btVector3(x, 8, 2)));
            }
        };
        for (int s = 0; s < 320; ++s) {
            w.step();
            const btOverlappingPairCache* cache = w.world().getBroadphase()->getOverlappingPairCache();
            btBroadphasePair* pairs = const_cast<btOverlappingPairCache*>(cache)->getOverlappingPairArrayPtr();
            for (int p = 0; p < cache->getNumOverlappingPairs(); ++p) {
                for (btBroadphaseProxy* proxy : {pairs[p].m_pProxy0, pairs[p].m_pProxy1}) {
                    auto* obj = static_cast<btCollisionObject*>(proxy->m_clientObject);
                    ASSERT_EQ(obj->getBroadphaseHandle(), proxy) << "pair with a stale proxy at step " << s;
                    ASSERT_TRUE(std::find(removed.begin(), removed.end(), obj) == removed.end())
                        << "pair with a removed object at step " << s;
                }
            }
        }
        // Every added body landed: it rests on something (has contacts) near the ground.
        const ContactMap contacts = contactsOf(w.world());
        int added = 0, resting = 0;
        for (int i = 1; i < w.nextIndex(); ++i) {
            auto* body = btRigidBody::upcast(w.objectByIndex(i));
            if (!body->isInWorld() || i < 11) continue;  // 1 + 10 stack boxes
            ++added;
            const bool touching = std::any_of(contacts.begin(), contacts.end(), [&](const auto& kv) {
                return kv.first.first == i || kv.first.second == i;
            });
            if (touching && body->getWorldTransform().getOrigin().y() < btScalar(5))
                ++resting;
            else
                std::printf("  body %d not resting: y %.3f, touching %d, state %d\n", i,
                            double(body->getWorldTransform().getOrigin().y()), int(touching),
                            body->getActivationState());
        }
        std::printf("[mid-step add/remove, %s] %d bodies added mid-step, %d resting on the stack or ground, %zu "
                    "removed\n",
                    kind == PipelineKind::Default ? "default" : "cullide", added, resting, removed.size());
        EXPECT_EQ(added, 20);
        EXPECT_EQ(resting, added);
        EXPECT_EQ(removed.size(), 10u);
    }
}

}  // namespace
}  // namespace cullide::test
