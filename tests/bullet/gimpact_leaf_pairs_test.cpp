// bullet::LeafPairSearch against Bullet's own btGImpactQuantizedBvh::find_collision: the same primitive pairs in the
// same order, for tori in many relative poses (apart, touching, interpenetrating, coincident, scaled, one triangle).
#include "BulletTestWorld.h"
#include "narrowphase/GImpactLeafPairs.h"
#include "narrowphase/GImpactMeshContacts.h"
#include "cullide/TaskPool.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <initializer_list>
#include <cmath>
#include <random>
#include <vector>

namespace cullide::test {
namespace {

std::vector<int> bulletPairs(const btGImpactBoxSet& set0, const btTransform& t0, const btGImpactBoxSet& set1,
                             const btTransform& t1) {
    btPairSet pairs;
    btGImpactBoxSet::find_collision(&set0, t0, &set1, t1, pairs);
    std::vector<int> out;
    for (int i = 0; i < pairs.size(); ++i) {
        out.push_back(pairs[i].m_index1);
        out.push_back(pairs[i].m_index2);
    }
    return out;
}

std::vector<int> ourPairs(const btGImpactBoxSet& set0, const btTransform& t0, const btGImpactBoxSet& set1,
                          const btTransform& t1) {
    bullet::LeafPairScratch scratch;
    std::vector<int> out;
    bullet::LeafPairSearch(set0, t0, set1, t1).descend({0, 0}, scratch, out);
    return out;
}

const btGImpactBoxSet& boxSetOf(btCollisionShape* shape) {
    return *static_cast<btGImpactMeshShape*>(shape)->getMeshPart(0)->getBoxSet();
}

btTransform randomPose(std::mt19937& rng, btScalar spread) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    btQuaternion q(u(rng), u(rng), u(rng), u(rng) + 1.5f);
    q.normalize();
    return btTransform(q, btVector3(spread * u(rng), spread * u(rng), spread * u(rng)));
}

/// A large torus (1,024 triangles, margin 0.02) and a small one (192, margin 0): their box sets.
struct TwoTori {
    ShapeStore shapes;
    const btGImpactBoxSet* sets[2] = {&boxSetOf(shapes.gimpactTorus(1.0f, 0.35f, 32, 16, 0.02f)),
                                      &boxSetOf(shapes.gimpactTorus(0.6f, 0.2f, 12, 8, 0.0f))};
};

TEST(GImpactLeafPairs, SamePairsInBulletsOrder) {
    const TwoTori tori;
    const btGImpactBoxSet* const* sets = tori.sets;
    std::mt19937 rng(7);
    int posesWithPairs = 0;
    std::size_t largest = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const btGImpactBoxSet& a = *sets[trial % 2];
        const btGImpactBoxSet& b = *sets[(trial / 2) % 2];
        const btScalar spread = trial < 100 ? btScalar(0.3) : trial < 200 ? btScalar(1.5) : btScalar(3.0);
        const btTransform t0 = randomPose(rng, spread);
        const btTransform t1 = trial % 17 == 0 ? t0 : randomPose(rng, spread);  // coincident now and then
        const std::vector<int> expected = bulletPairs(a, t0, b, t1);
        ASSERT_EQ(ourPairs(a, t0, b, t1), expected) << "trial " << trial;
        if (!expected.empty()) ++posesWithPairs;
        largest = std::max(largest, expected.size() / 2);
    }
    // The poses must exercise the search: most overlap, some heavily (not a test of empty lists).
    EXPECT_GT(posesWithPairs, 150);
    EXPECT_GT(largest, 1000u);
}

TEST(GImpactLeafPairs, FarAwayFromTheOriginAndScaled) {
    ShapeStore shapes;
    auto* torus = static_cast<btGImpactMeshShape*>(shapes.gimpactTorus(1.0f, 0.35f, 24, 12, 0.01f));
    torus->setLocalScaling(btVector3(2.0f, 0.5f, 1.0f));
    torus->updateBound();
    const btGImpactBoxSet& set = *torus->getMeshPart(0)->getBoxSet();
    std::mt19937 rng(11);
    for (int trial = 0; trial < 60; ++trial) {
        btTransform t0 = randomPose(rng, 0.5f);
        btTransform t1 = randomPose(rng, 0.5f);
        const btVector3 far(btScalar(1e4) * btScalar(trial), btScalar(-3e3), btScalar(2e4));
        t0.setOrigin(t0.getOrigin() + far);
        t1.setOrigin(t1.getOrigin() + far);
        ASSERT_EQ(ourPairs(set, t0, set, t1), bulletPairs(set, t0, set, t1)) << "trial " << trial;
    }
}

// Meshes whose vertices lie far from the origin (as world-space meshes deformed in place are): Bullet's boxes there
// are rounded by many steps of its quantization grid, and the search's boxes on the other grid must keep every pair
// Bullet's rounded test keeps. Poses turn the second mesh about the meshes' centre, from apart to coincident.
TEST(GImpactLeafPairs, VerticesFarFromTheOrigin) {
    ShapeStore shapes;
    const btVector3 centre(btScalar(3e3), btScalar(-2e3), btScalar(5e3));
    const btGImpactBoxSet& a = boxSetOf(shapes.gimpactTorus(1.0f, 0.35f, 24, 12, 0.0f, centre));
    const btGImpactBoxSet& b = boxSetOf(shapes.gimpactTorus(0.8f, 0.3f, 20, 10, 0.01f, centre));
    std::mt19937 rng(17);
    std::size_t pairs = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const btTransform turn = randomPose(rng, trial < 100 ? btScalar(0.4) : btScalar(1.5));
        // `turn` about the centre: x -> R (x - centre) + centre + d.
        const btTransform t1(turn.getBasis(), centre - turn.getBasis() * centre + turn.getOrigin());
        const btTransform t0 = trial % 11 == 0 ? t1 : btTransform::getIdentity();
        const std::vector<int> expected = bulletPairs(a, t0, b, t1);
        ASSERT_EQ(ourPairs(a, t0, b, t1), expected) << "trial " << trial;
        pairs += expected.size() / 2;
    }
    EXPECT_GT(pairs, 10000u);
}

// Every node pair, not only those a descent reaches, is kept or pruned as Bullet's test on the two nodes' stored
// boxes (btAABB::overlapping_trans_cache, its 6 face axes) keeps or prunes it: the integer decisions' allowance
// covers Bullet's rounding, and the sure depth leaves no pair to a wrong guess. (Bullet's |R| + 1e-6 widening is
// not isolated by these poses: removing its term from the allowance fails nothing here.)
// Meshes near the origin and ~5,000 units from it (Bullet's rounding there spans many grid steps), turned about
// their centre from apart to coincident, and moved without turning (frames that differ by a translation only, as
// those of deforming meshes kept in world space: there one overlap decides). (A leaf-pair list can hide a wrong
// decision at an inner node whose subtrees hold no kept leaf pair; this test cannot.)
TEST(GImpactLeafPairs, EveryNodePairDecidedAsBulletsTestDecidesIt) {
    ShapeStore shapes;
    std::mt19937 rng(29);
    std::size_t kept = 0, pruned = 0;
    struct Scene {
        btVector3 centre;
        btScalar small;   // the second torus's size relative to the first's
        btVector3 place;  // the second torus's centre relative to the first's
    };
    // The third: a torus 100 times smaller on the first one's surface (grid steps a hundredfold apart).
    const btVector3 far(btScalar(3e3), btScalar(-2e3), btScalar(5e3)), none(0, 0, 0);
    for (const Scene& scene : {Scene{none, 1, none}, Scene{far, 1, none},
                               Scene{none, btScalar(0.01), btVector3(btScalar(1.35), 0, 0)}}) {
        const btVector3& centre = scene.centre;
        const btVector3 centre1 = centre + scene.place;
        const btGImpactBoxSet& a = boxSetOf(shapes.gimpactTorus(1.0f, 0.35f, 24, 12, 0.0f, centre));
        const btGImpactBoxSet& b = boxSetOf(
            shapes.gimpactTorus(0.8f * scene.small, 0.3f * scene.small, 20, 10, 0.01f * scene.small, centre1));
        bullet::LeafPairScratch scratch;
        for (int trial = 0; trial < 12; ++trial) {
            const btTransform turn = randomPose(rng, (trial % 4 < 2 ? btScalar(0.3) : btScalar(1.2)) * scene.small);
            const btTransform t1 =
                trial < 8 ? btTransform(turn.getBasis(), centre1 - turn.getBasis() * centre1 + turn.getOrigin())
                          : btTransform(btMatrix3x3::getIdentity(), turn.getOrigin());  // moved, not turned
            const btTransform t0 = trial == 0 || trial == 8 ? t1 : btTransform::getIdentity();
            const bullet::LeafPairSearch search(a, t0, b, t1);
            if (!search.rootsOverlap()) continue;  // Bullet's descent stops at the roots (their 15-axis test)
            BT_BOX_BOX_TRANSFORM_CACHE cache;
            cache.calc_from_homogenic(t0, t1);
            for (int n0 = 0; n0 < a.getNodeCount(); ++n0) {
                btAABB box0;
                a.getNodeBound(n0, box0);
                for (int n1 = n0 == 0 ? 1 : 0; n1 < b.getNodeCount(); ++n1) {
                    btAABB box1;
                    b.getNodeBound(n1, box1);
                    const bool bullet = box0.overlapping_trans_cache(box1, cache, false);
                    ASSERT_EQ(search.keeps(n0, n1, scratch), bullet)
                        << "centre " << centre.x() << ", size " << scene.small << ", trial " << trial << ", nodes "
                        << n0 << ", " << n1;
                    ++(bullet ? kept : pruned);
                }
            }
        }
    }
    EXPECT_GT(kept, 100000u);
    EXPECT_GT(pruned, 100000u);
}

// The search cut into parts (for the narrow-phase threads): the parts' pairs, concatenated in split order, are
// Bullet's pairs in Bullet's order, for every part count, small trees and large, apart to coincident.
TEST(GImpactLeafPairs, SplitPartsConcatenateToBulletsPairs) {
    const TwoTori tori;
    const btGImpactBoxSet* const* sets = tori.sets;
    std::mt19937 rng(13);
    bullet::LeafPairScratch scratch;
    std::vector<bullet::NodePair> parts;
    std::size_t mostParts = 0;
    for (int trial = 0; trial < 120; ++trial) {
        const btGImpactBoxSet& a = *sets[trial % 2];
        const btGImpactBoxSet& b = *sets[(trial / 2) % 2];
        const btTransform t0 = randomPose(rng, trial < 60 ? btScalar(0.3) : btScalar(2.0));
        const btTransform t1 = trial % 13 == 0 ? t0 : randomPose(rng, trial < 60 ? btScalar(0.3) : btScalar(2.0));
        const std::vector<int> expected = bulletPairs(a, t0, b, t1);
        const bullet::LeafPairSearch search(a, t0, b, t1);
        for (std::size_t target : {1, 2, 3, 8, 33, 1000}) {
            search.split(target, scratch, parts);
            std::vector<int> got;
            for (const bullet::NodePair& part : parts) search.descend(part, scratch, got);
            ASSERT_EQ(got, expected) << "trial " << trial << ", target " << target << ", " << parts.size() << " parts";
            if (target == 1) {
                EXPECT_LE(parts.size(), 1u);
            }
            mostParts = std::max(mostParts, parts.size());
        }
    }
    EXPECT_GT(mostParts, 500u);  // the large targets do cut the search into many parts
}

TEST(GImpactLeafPairs, SmallTreeAgainstLargeTree) {
    ShapeStore shapes;
    btCollisionShape* one = shapes.gimpactTorus(1.0f, 0.3f, 3, 3, 0.0f);  // 18 triangles, a shallow tree
    btCollisionShape* many = shapes.gimpactTorus(1.0f, 0.3f, 16, 8, 0.0f);
    std::mt19937 rng(3);
    for (int trial = 0; trial < 100; ++trial) {
        const btTransform t0 = randomPose(rng, 0.5f);
        const btTransform t1 = randomPose(rng, 0.5f);
        ASSERT_EQ(ourPairs(boxSetOf(one), t0, boxSetOf(many), t1), bulletPairs(boxSetOf(one), t0, boxSetOf(many), t1));
        ASSERT_EQ(ourPairs(boxSetOf(many), t0, boxSetOf(one), t1), bulletPairs(boxSetOf(many), t0, boxSetOf(one), t1));
    }
}

}  // namespace
}  // namespace cullide::test

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

/// Two computed points alike in every bit and identifier.
bool sameContact(const bullet::MeshContact& x, const bullet::MeshContact& y) {
    return x.point == y.point && x.normal == y.normal && x.distance == y.distance && x.part0 == y.part0 &&
           x.face0 == y.face0 && x.part1 == y.part1 && x.face1 == y.face1;
}

/// The points of the batch's lists, in their order.
std::vector<bullet::MeshContact> flatten(const bullet::ContactLists& lists) {
    std::vector<bullet::MeshContact> points;
    lists.forEach([&](const bullet::MeshContact& c) { points.push_back(c); });
    return points;
}

// The contacts computed ahead are used only for the inputs they were computed for: another transform (by one bit),
// another shape or the objects the other way round find nothing, and the algorithm computes the pair itself.
TEST(GImpactMeshContacts, AheadResultsMatchTheirInputsExactly) {
    ShapeStore shapes;
    auto* torus = static_cast<btGImpactMeshShape*>(shapes.gimpactTorus(2, btScalar(0.5), 48, 16, btScalar(0.01)));
    auto* other = static_cast<btGImpactMeshShape*>(shapes.gimpactTorus(2, btScalar(0.5), 24, 10, btScalar(0.01)));
    btCollisionObject a, b;
    std::mt19937 rng(19);
    const btTransform t0 = randomPose(rng, 0.3f), t1 = randomPose(rng, 0.3f);
    std::vector<bullet::MeshContact> sequential;
    bullet::meshPairContacts(*torus, t0, *torus, t1, bullet::threadScratch(), sequential);
    ASSERT_GT(sequential.size(), 4u);
    TaskPool pool(3);
    bullet::MeshContactBatch batch;
    for (TaskPool* p : {static_cast<TaskPool*>(nullptr), &pool}) {
        batch.clear();
        batch.add(&a, &b, *torus, *torus, t0, t1);
        // find() is asked while the batch runs (as the dispatch loop asks): it waits for, or runs, the pair's tasks.
        batch.run(p, [&] {
            btTransform nudged = t1;
            nudged.getOrigin().setX(std::nextafter(t1.getOrigin().x(), btScalar(1e30)));
            EXPECT_EQ(batch.find(&a, &b, torus, torus, t0, nudged), nullptr);
            EXPECT_EQ(batch.find(&a, &b, torus, other, t0, t1), nullptr);
            EXPECT_EQ(batch.find(&b, &a, torus, torus, t1, t0), nullptr);
            const bullet::ContactLists* found = batch.find(&a, &b, torus, torus, t0, t1);
            ASSERT_NE(found, nullptr);
            const std::vector<bullet::MeshContact> points = flatten(*found);
            ASSERT_EQ(points.size(), sequential.size());
            EXPECT_EQ(found->size(), sequential.size());
            for (std::size_t i = 0; i < sequential.size(); ++i)
                EXPECT_TRUE(sameContact(points[i], sequential[i])) << "point " << i;
            EXPECT_EQ(batch.find(&a, &b, torus, torus, t0, t1), found) << "asked again: the same list";
        });
        EXPECT_EQ(batch.find(&a, &b, torus, torus, t0, t1), nullptr) << "only while the batch runs";
    }
    batch.clear();
    EXPECT_EQ(batch.find(&a, &b, torus, torus, t0, t1), nullptr);
}

// Large pairs' search parts share each body's prepared triangles (one store per part and transform, a shape shared by
// two bodies getting two) within a memory budget; beyond it a part's tasks prepare their own. Both ways, and with a
// budget for one store only, the points are the sequential computation's, bit for bit, whatever the threads.
TEST(GImpactMeshContacts, SharedTrianglesWithinTheBudgetOrEachTaskItsOwn) {
    ShapeStore shapes;
    auto* fine = static_cast<btGImpactMeshShape*>(shapes.gimpactTorus(2, btScalar(0.5), 128, 32, btScalar(0.01)));
    btCollisionObject a, b, c;
    const std::size_t oneStore =
        std::size_t(fine->getMeshPart(0)->getNumChildShapes()) * sizeof(bullet::PreparedTriangle);
    const auto same = [](const std::vector<bullet::MeshContact>& x, const std::vector<bullet::MeshContact>& y) {
        return std::equal(x.begin(), x.end(), y.begin(), y.end(), sameContact);
    };
    TaskPool pool(3);
    std::mt19937 rng(23);
    for (std::size_t budget : {std::size_t{0}, oneStore, std::size_t{64} << 20}) {
        bullet::MeshContactBatch batch;
        batch.setSharedTriangleBudget(budget);
        for (int round = 0; round < 3; ++round) {  // new poses each dispatch: the reused stores must not keep triangles
            const btTransform t0 = randomPose(rng, 0.3f), t1 = randomPose(rng, 0.3f), t2 = randomPose(rng, 0.3f);
            std::vector<bullet::MeshContact> sequential01, sequential12;
            bullet::meshPairContacts(*fine, t0, *fine, t1, bullet::threadScratch(), sequential01);
            bullet::meshPairContacts(*fine, t1, *fine, t2, bullet::threadScratch(), sequential12);
            ASSERT_GT(sequential01.size() + sequential12.size(), 4u);
            batch.clear();
            batch.add(&a, &b, *fine, *fine, t0, t1);
            batch.add(&b, &c, *fine, *fine, t1, t2);  // body b's store serves both pairs
            batch.run(&pool, [&] {
                const bullet::ContactLists* found01 = batch.find(&a, &b, fine, fine, t0, t1);
                const bullet::ContactLists* found12 = batch.find(&b, &c, fine, fine, t1, t2);
                ASSERT_NE(found01, nullptr);
                ASSERT_NE(found12, nullptr);
                EXPECT_TRUE(same(flatten(*found01), sequential01)) << "budget " << budget << ", round " << round;
                EXPECT_TRUE(same(flatten(*found12), sequential12)) << "budget " << budget << ", round " << round;
            });
            EXPECT_GT(batch.taskCount(), 2u);  // the pairs were cut into parts
            EXPECT_EQ(batch.sharedStores(), budget == 0 ? 0u : budget == oneStore ? 1u : 3u);
        }
    }
}

}  // namespace
}  // namespace cullide::test
