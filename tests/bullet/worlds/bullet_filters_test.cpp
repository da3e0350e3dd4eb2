// Scene 5: collision filter groups/masks and overlap filter callbacks, and masks written through the proxy, CULLIDE
// against Bullet's default pipeline.
#include "SceneSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

namespace cullide::test {
namespace {

constexpr int kRed = 64;
constexpr int kBlue = 128;

/// Rejects pairs of two objects whose user indices are both multiples of 5.
struct NoFives : btOverlapFilterCallback {
    bool needBroadphaseCollision(btBroadphaseProxy* p0, btBroadphaseProxy* p1) const override {
        const bool masks = (p0->m_collisionFilterGroup & p1->m_collisionFilterMask) != 0 &&
                           (p1->m_collisionFilterGroup & p0->m_collisionFilterMask) != 0;
        const int a = static_cast<btCollisionObject*>(p0->m_clientObject)->getUserIndex();
        const int b = static_cast<btCollisionObject*>(p1->m_clientObject)->getUserIndex();
        return masks && !(a % 5 == 0 && b % 5 == 0);
    }
};

struct FilterScene {
    ShapeStore shapes;
    btCollisionShape* ground = shapes.box(btVector3(10, 1, 10));
    btCollisionShape* box = shapes.box(btVector3(btScalar(0.4), btScalar(0.4), btScalar(0.4)));
    btCollisionShape* sphere = shapes.sphere(btScalar(0.4));
    NoFives noFives;

    void populate(TestWorld& w) {
        w.world().getPairCache()->setOverlapFilterCallback(&noFives);
        w.addBody(ground, 0, btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)),
                  btBroadphaseProxy::StaticFilter, kRed | kBlue);
        for (int k = 0; k < 40; ++k) {
            // A narrow column: falling bodies pile up and meet each other.
            const btVector3 p(btScalar(0.3 * ((k * 7) % 5 - 2)), btScalar(1 + 0.9 * k), btScalar(0.3 * ((k * 3) % 5 - 2)));
            const bool red = k % 2 == 0;
            w.addBody(k % 3 == 0 ? sphere : box, 1, btTransform(btQuaternion(btScalar(k), 0, 0), p), red ? kRed : kBlue,
                      red ? (btBroadphaseProxy::StaticFilter | kRed) : btBroadphaseProxy::StaticFilter);
        }
    }
};

void expectCacheRespectsFilters(TestWorld& w, const btOverlapFilterCallback& filter, int step) {
    btOverlappingPairCache* cache = w.world().getPairCache();
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        btBroadphasePair& p = cache->getOverlappingPairArrayPtr()[i];
        ASSERT_TRUE(filter.needBroadphaseCollision(p.m_pProxy0, p.m_pProxy1))
            << "filtered pair in the cache at step " << step;
    }
}

TEST(BulletFilters, GroupsMasksAndOverlapCallbackMirrored) {
    CULLIDE_BULLET_REQUIRE_GL();
    FilterScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld cullide(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(cullide);
    MirrorOptions options;
    options.steps = 200;
    std::size_t redRed = 0;
    options.each = [&](int step, TestWorld&, TestWorld& b) {
        expectCacheRespectsFilters(b, scene.noFives, step);
        // The filters did something: red-red contacts exist, no blue-blue or red-blue ones.
        for (const auto& [key, pc] : contactsOf(b.world())) {
            if (key.first == 0) continue;
            const bool redA = (key.first - 1) % 2 == 0, redB = (key.second - 1) % 2 == 0;
            ASSERT_TRUE(redA && redB) << "contact between " << key.first << " and " << key.second;
            ASSERT_FALSE(key.first % 5 == 0 && key.second % 5 == 0);
            ++redRed;
        }
    };
    const MirrorRun run = runMirrored(reference, cullide, options);
    printMirrorRun("filters", run);
    expectAgreement(run, 1000);
    EXPECT_GT(redRed, 0u);
}

/// A mask written through the proxy acts as in Bullet: btDbvtBroadphase keeps the pairs it already has (the
/// narrow phase does not read masks) and makes no new pair the mask refuses; removing the proxy's pairs (Bullet's
/// recipe after a filter change) ends the pair and the contact. Both pipelines side by side.
TEST(BulletFilters, MaskWrittenThroughTheProxyActsAsInBullet) {
    CULLIDE_BULLET_REQUIRE_GL();
    FilterScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld w(PipelineKind::Cullide);
    scene.populate(reference);
    scene.populate(w);
    for (int s = 0; s < 150; ++s) {
        reference.step();
        mirrorState(reference, w);
        w.step();
    }
    // Find a red body resting on another red body, then let it ignore red bodies by writing the proxy's mask.
    int upper = -1, lower = -1;
    for (const auto& [key, pc] : contactsOf(w.world()))
        if (key.first != 0 && (key.first - 1) % 2 == 0 && (key.second - 1) % 2 == 0) {
            upper = key.second;
            lower = key.first;
            break;
        }
    ASSERT_GE(upper, 0) << "no red-red contact to work with";
    const std::pair<int, int> key(std::min(upper, lower), std::max(upper, lower));
    for (TestWorld* x : {&reference, &w}) {
        btCollisionObject* body = x->objectByIndex(upper);
        body->getBroadphaseHandle()->m_collisionFilterMask = btBroadphaseProxy::StaticFilter;
        body->activate(true);
    }
    reference.step();
    mirrorState(reference, w);
    w.step();
    EXPECT_EQ(pairsOf(reference.world()).count(key), 1u) << "Bullet keeps an existing pair";
    EXPECT_EQ(pairsOf(w.world()).count(key), 1u) << "an existing pair stays, as in Bullet";
    for (TestWorld* x : {&reference, &w}) {
        btCollisionObject* body = x->objectByIndex(upper);
        x->world().getPairCache()->removeOverlappingPairsContainingProxy(body->getBroadphaseHandle(),
                                                                         x->world().getDispatcher());
    }
    reference.step();
    mirrorState(reference, w);
    w.step();
    EXPECT_EQ(pairsOf(reference.world()).count(key), 0u);
    EXPECT_EQ(pairsOf(w.world()).count(key), 0u);
    btOverlappingPairCache* cache = w.world().getPairCache();
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        btBroadphasePair& p = cache->getOverlappingPairArrayPtr()[i];
        EXPECT_TRUE(scene.noFives.needBroadphaseCollision(p.m_pProxy0, p.m_pProxy1));
    }
    EXPECT_EQ(contactsOf(w.world()).count(key), 0u);
}

}  // namespace
}  // namespace cullide::test
