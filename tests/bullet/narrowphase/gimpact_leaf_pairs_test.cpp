// bullet::LeafPairSearch (narrowphase/GImpactLeafPairs.h) against Bullet's own btGImpactQuantizedBvh::find_collision:
// the same primitive pairs in the same order, for tori in many relative poses (apart, touching, interpenetrating,
// coincident, scaled, one triangle), far from the origin, node pair by node pair, and cut into parts.
#include "BulletTestWorld.h"
#include "RandomPose.h"
#include "narrowphase/GImpactLeafPairs.h"

#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <gtest/gtest.h>

#include <algorithm>
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
