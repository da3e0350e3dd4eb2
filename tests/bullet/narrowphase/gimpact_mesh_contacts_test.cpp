// The GImpact mesh-mesh contacts computed ahead on the narrow-phase threads (narrowphase/GImpactMeshContacts.h): used
// only for the inputs they were computed for, and the same points, bit for bit, with shared prepared triangles
// within the memory budget or each task preparing its own.
#include "BulletTestWorld.h"
#include "RandomPose.h"
#include "cullide/TaskPool.h"
#include "narrowphase/GImpactMeshContacts.h"

#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace cullide::test {
namespace {

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
