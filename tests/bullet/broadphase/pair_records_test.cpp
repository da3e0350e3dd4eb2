// The hand-off from the broadphase to the dispatcher (broadphase/PairRecords.h), through PairRecords' own API: the
// records are made from a culling frame of real collision objects and proxies (CullFrame) and a culler's verdicts
// written by hand (Result), as CullideBroadphase makes them each step. Guarded: a record is found for its two objects
// in either order, `swapped` saying which way round; only for those two proxies; only while both objects keep the
// recorded shapes and world transforms (bit for bit), a compound's child wrapper on the compound's side excepted;
// pruned pairs carry empty lists; kept pairs carry the triangles of the right side in Bullet's names and in record
// orientation, sorted; other kept pairs get no record; interpenetrating GImpact pairs skip the culler for
// kPenetrationRecheck steps; records go with their proxy and with the step.
#include "BulletTestWorld.h"
#include "ProxyBody.h"
#include "broadphase/CullFrame.h"
#include "broadphase/PairRecords.h"

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionShapes/btCompoundShape.h>
#include <BulletCollision/CollisionShapes/btStridingMeshInterface.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/CollisionShapes/btTriangleMeshShape.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace cullide::test {
namespace {

using bullet::CullFrame;
using bullet::PairRecords;

using Body = ProxyBody;

/// find() for the two bodies' own wrappers (the object's shape and world transform), x as wrapper 0.
const PairTriangles* lookUp(const PairRecords& records, const Body& x, const Body& y, bool& swapped) {
    const btCollisionObjectWrapper wx(nullptr, x.object.getCollisionShape(), &x.object, x.object.getWorldTransform(),
                                      -1, -1);
    const btCollisionObjectWrapper wy(nullptr, y.object.getCollisionShape(), &y.object, y.object.getWorldTransform(),
                                      -1, -1);
    return records.find(&wx, &wy, swapped);
}

const PairTriangles* lookUp(const PairRecords& records, const Body& x, const Body& y) {
    bool swapped = false;
    return lookUp(records, x, y, swapped);
}

/// One step's culling frame of `pairs` and the verdicts `kept` on some of them: kept[k] lists the culler's triangle
/// pairs of (first, second) of pair k, in the culler's object order (first as ObjectPair::a); pairs not in `kept` are
/// left out of the result (proven apart). Records them as CullideBroadphase does.
struct Step {
    CullFrame frame;
    PairRecords records;
    CullideFrameStats stats;
    std::uint64_t number = 1;  ///< the next step's number

    struct Verdict {
        const Body* first;
        const Body* second;
        std::vector<TrianglePair> triangles;  ///< empty: kept without triangles
    };

    void run(const std::vector<std::pair<Body*, Body*>>& pairs, const std::vector<Verdict>& kept,
             bool deepPenetrationFallback = true) {
        stats = CullideFrameStats{};
        records.beginStep(number, deepPenetrationFallback);
        frame.beginStep();
        std::vector<CullFrame::ProxyPair> candidates;
        for (const auto& [a, b] : pairs) candidates.emplace_back(&a->proxy, &b->proxy);
        frame.build(candidates, number, stats);
        Result result;
        for (const Verdict& v : kept) {
            ObjectPair op;
            op.a = indexOf(*v.first);
            op.b = indexOf(*v.second);
            op.hasTriangles = !v.triangles.empty();
            op.triangles = v.triangles;
            result.pairs.push_back(op);
        }
        records.recordVerdicts(result, frame, deepPenetrationFallback, stats);
        ++number;
    }

    std::uint32_t indexOf(const Body& body) const {
        for (std::uint32_t i = 0; i < frame.objects().size(); ++i)
            if (frame.proxyOf(i) == &body.proxy) return i;
        ADD_FAILURE() << "body not in the frame";
        return 0;
    }

    /// The culler's local triangle mesh of the body (its ShapeTriangles, as the frame built them).
    const TriangleMesh& localMesh(const Body& body) { return frame.culled(&body.proxy).geometry->local; }
};

/// Every triangle of a triangle-mesh shape as Bullet's processAllTriangles yields it: (part, index) -> 3 vertices.
std::map<std::pair<int, int>, std::array<btVector3, 3>> bulletTriangles(const btCollisionShape* shape) {
    struct Collect final : btInternalTriangleIndexCallback {
        std::map<std::pair<int, int>, std::array<btVector3, 3>> out;
        void internalProcessTriangleIndex(btVector3* t, int part, int index) override {
            out[{part, index}] = {t[0], t[1], t[2]};
        }
    } collect;
    const btVector3 big(btScalar(1e30), btScalar(1e30), btScalar(1e30));
    static_cast<const btTriangleMeshShape*>(shape)->getMeshInterface()->InternalProcessAllTriangles(&collect, -big,
                                                                                                   big);
    return collect.out;
}

/// Triangles u of `mesh` other than t that share a vertex position with t (their boxes touch: pairs the culler may
/// keep).
std::vector<std::uint32_t> neighbours(const TriangleMesh& mesh, std::uint32_t t) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t u = 0; u < mesh.triangles.size(); ++u) {
        if (u == t) continue;
        bool shares = false;
        for (std::uint32_t v : mesh.triangles[u])
            for (std::uint32_t w : mesh.triangles[t]) shares = shares || mesh.vertices[v] == mesh.vertices[w];
        if (shares) out.push_back(u);
    }
    return out;
}

/// The triangle of `mesh` whose first vertex lies farthest from triangle t's first vertex.
std::uint32_t farthestFrom(const TriangleMesh& mesh, std::uint32_t t) {
    const Vec3 p = mesh.vertices[mesh.triangles[t][0]];
    std::uint32_t best = 0;
    for (std::uint32_t u = 1; u < mesh.triangles.size(); ++u)
        if ((mesh.vertices[mesh.triangles[u][0]] - p).norm() > (mesh.vertices[mesh.triangles[best][0]] - p).norm())
            best = u;
    return best;
}

btTransform at(double x, double y, double z) {
    return btTransform(btQuaternion::getIdentity(), btVector3(btScalar(x), btScalar(y), btScalar(z)));
}

/// A hull (proxy id 7) resting on a landscape (proxy id 3), a box near both (id 5), and a second hull (id 11).
struct HullOnLandscape {
    ShapeStore shapes;
    Body hull{shapes.hull(btVector3(0.6f, 0.4f, 0.5f), 24, 3), at(0.5, 0.6, 0.5), 7};
    Body landscape{shapes.landscape(8, 1, btScalar(0.3)), at(-4, 0, -4), 3};
    Body box{shapes.box(btVector3(0.3f, 0.3f, 0.3f)), at(1.2, 0.6, 0.5), 5};
    Body hull2{shapes.hull(btVector3(0.5f, 0.5f, 0.5f), 20, 4), at(-0.4, 0.7, 0.4), 11};
};

TEST(PairRecords, PrunedPairsHaveARecordWithEmptyLists) {
    HullOnLandscape s;
    Step step;
    step.run({{&s.hull, &s.landscape}, {&s.box, &s.landscape}}, {});
    EXPECT_EQ(step.stats.prunedPairs, 2u);
    for (const Body* other : {&s.hull, &s.box}) {
        const PairTriangles* rec = lookUp(step.records, *other, s.landscape);
        ASSERT_NE(rec, nullptr);
        EXPECT_TRUE(rec->pruned);
        EXPECT_FALSE(rec->interpenetrating);
        EXPECT_TRUE(rec->pairs.empty());
        EXPECT_TRUE(rec->meshTriangles.empty());
        EXPECT_TRUE(rec->meshTriangleVertices.empty());
    }
}

TEST(PairRecords, FoundInEitherOrderWithSwappedSaying) {
    HullOnLandscape s;
    Step step;
    step.run({{&s.hull, &s.landscape}}, {{&s.hull, &s.landscape, {{0, 10}}}});
    // The record's first object is the landscape (the lower unique id, 3), whatever the culler's order.
    bool swapped = true;
    const PairTriangles* direct = lookUp(step.records, s.landscape, s.hull, swapped);
    ASSERT_NE(direct, nullptr);
    EXPECT_FALSE(swapped);
    swapped = false;
    const PairTriangles* reversed = lookUp(step.records, s.hull, s.landscape, swapped);
    EXPECT_EQ(reversed, direct);
    EXPECT_TRUE(swapped);
    EXPECT_FALSE(direct->pruned);
}

TEST(PairRecords, KeptMeshPairsHoldTheMeshSidesTrianglesAsBulletNamesThem) {
    HullOnLandscape s;
    ShapeStore shapes;
    Body torus{shapes.gimpactTorus(btScalar(0.5), btScalar(0.15), 12, 6, btScalar(0.01)), at(-1.0, 0.6, -1.0), 9};
    Step step;
    // The landscape enters the frame first: it is ObjectPair::a of the torus pair and ObjectPair::b of the hull pair,
    // so the mesh side is a in one verdict and b in the other. Mesh triangles repeat and come unsorted.
    step.run({{&s.landscape, &torus}, {&s.hull, &s.landscape}},
             {{&s.landscape, &torus, {{40, 1}, {12, 2}, {40, 3}, {7, 0}}},
              {&s.hull, &s.landscape, {{2, 57}, {0, 12}, {5, 57}, {1, 33}}}});
    EXPECT_EQ(step.stats.cullerPairs, 2u);
    EXPECT_EQ(step.stats.trianglePairs, 3u + 3u);
    const auto bullet = bulletTriangles(s.landscape.object.getCollisionShape());
    const std::pair<const Body*, std::vector<int>> expected[] = {{&torus, {7, 12, 40}}, {&s.hull, {12, 33, 57}}};
    for (const auto& [other, indices] : expected) {
        const PairTriangles* rec = lookUp(step.records, *other, s.landscape);
        ASSERT_NE(rec, nullptr);
        EXPECT_FALSE(rec->pruned);
        EXPECT_TRUE(rec->pairs.empty());
        ASSERT_EQ(rec->meshTriangles.size(), indices.size());
        ASSERT_EQ(rec->meshTriangleVertices.size(), 3 * indices.size());
        for (std::size_t k = 0; k < indices.size(); ++k) {
            // The landscape is one part whose triangles the culler numbers as Bullet does.
            EXPECT_EQ(rec->meshTriangles[k], (BulletTriangle{0, indices[k]})) << k;
            const auto& vertices = bullet.at({0, indices[k]});
            for (int v = 0; v < 3; ++v) EXPECT_EQ(rec->meshTriangleVertices[3 * k + std::size_t(v)], vertices[v]) << k;
        }
    }
}

TEST(PairRecords, GImpactPairsAreInRecordOrientationAndSorted) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(btScalar(1), btScalar(0.3), 16, 8, btScalar(0.01));
    // Two coincident tori; the culler's first object (a, entered first) has the higher unique id: the record's first
    // is b.
    Body a{torus, at(0, 1, 0), 9};
    Body b{torus, at(0, 1, 0), 4};
    Step step;
    step.run({{&a, &b}}, {}, false);  // builds the frame (and the meshes) to choose the triangles from
    const TriangleMesh& mesh = step.localMesh(a);
    const std::uint32_t t = 5;
    std::vector<std::uint32_t> near = neighbours(mesh, t);
    near.erase(std::remove_if(near.begin(), near.end(), [&](std::uint32_t x) { return x < t; }), near.end());
    ASSERT_GE(near.size(), 2u);
    const std::uint32_t u = near[0], w = near[1];  // t < u < w
    // Culler pairs (a's triangle, b's triangle), sorted as the culler sorts them: (t, t), (t, u), (w, t). In record
    // orientation (t, t), (u, t), (t, w): out of order until sorted.
    const std::vector<TrianglePair> culled = {{t, t}, {t, u}, {w, t}};
    step.run({{&a, &b}}, {{&a, &b, culled}}, false);
    const PairTriangles* rec = lookUp(step.records, b, a);
    ASSERT_NE(rec, nullptr);
    EXPECT_FALSE(rec->interpenetrating);
    EXPECT_FALSE(rec->pruned);
    // (b's triangle, a's triangle), sorted by (a.part, b.part, a.index, b.index).
    const std::vector<std::pair<int, int>> expected = {{int(t), int(t)}, {int(t), int(w)}, {int(u), int(t)}};
    ASSERT_EQ(rec->pairs.size(), expected.size());
    for (std::size_t k = 0; k < expected.size(); ++k) {
        EXPECT_EQ(rec->pairs[k].a, (BulletTriangle{0, expected[k].first})) << k;
        EXPECT_EQ(rec->pairs[k].b, (BulletTriangle{0, expected[k].second})) << k;
    }
    EXPECT_EQ(step.stats.trianglePairs, expected.size());
}

TEST(PairRecords, InterpenetratingGImpactPairsSkipTheCullerForAFewSteps) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(btScalar(1), btScalar(0.3), 16, 8, btScalar(0.01));
    Body a{torus, at(0, 1, 0), 2};
    Body b{torus, at(0, 1, 0), 6};
    Step step;
    step.run({{&a, &b}}, {}, false);  // builds the frame (and the meshes) to choose the triangles from
    // A pair of triangles far apart, then coincident triangles, which meet: the meshes interpenetrate.
    const std::vector<TrianglePair> culled = {{0, farthestFrom(step.localMesh(a), 0)}, {5, 5}};
    step.number = 10;
    step.run({{&a, &b}}, {{&a, &b, culled}});
    const PairTriangles* rec = lookUp(step.records, a, b);
    ASSERT_NE(rec, nullptr);
    EXPECT_TRUE(rec->interpenetrating);
    EXPECT_TRUE(rec->pairs.empty()) << "Bullet's full algorithm runs: no list";
    EXPECT_EQ(step.stats.interpenetratingPairs, 1u);
    // Skips the culler through step 10 + kPenetrationRecheck, then is culled again.
    for (std::uint64_t s = 11; s <= 10 + PairRecords::kPenetrationRecheck + 1; ++s) {
        step.records.beginStep(s, true);
        EXPECT_EQ(step.records.recentlyPenetrating(&a.proxy, &b.proxy), s <= 10 + PairRecords::kPenetrationRecheck)
            << "step " << s;
        EXPECT_EQ(step.records.recentlyPenetrating(&b.proxy, &a.proxy), s <= 10 + PairRecords::kPenetrationRecheck)
            << "step " << s;
    }
    // Without the fallback the pair is forgotten at once.
    step.number = 20;
    step.run({{&a, &b}}, {{&a, &b, culled}});
    step.records.beginStep(21, false);
    EXPECT_FALSE(step.records.recentlyPenetrating(&a.proxy, &b.proxy));
    // A pair that skips the culler is recorded as interpenetrating.
    step.records.recordPenetrating(&b.proxy, &a.proxy);
    bool swapped = true;
    rec = lookUp(step.records, a, b, swapped);
    ASSERT_NE(rec, nullptr);
    EXPECT_TRUE(rec->interpenetrating);
    EXPECT_FALSE(rec->pruned);
    EXPECT_FALSE(swapped);
}

TEST(PairRecords, OtherKeptPairsGetNoRecord) {
    HullOnLandscape s;
    Step step;
    // Hull-hull kept with triangles (Bullet's algorithm reads no triangle), hull-landscape kept without triangles.
    step.run({{&s.hull, &s.hull2}, {&s.hull, &s.landscape}},
             {{&s.hull, &s.hull2, {{0, 0}}}, {&s.hull, &s.landscape, {}}});
    EXPECT_EQ(lookUp(step.records, s.hull, s.hull2), nullptr);
    EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), nullptr);
    EXPECT_EQ(step.stats.cullerPairs, 2u);
    EXPECT_EQ(step.stats.prunedPairs, 0u);
}

TEST(PairRecords, NotFoundForOtherObjectsOrProxies) {
    HullOnLandscape s;
    Step step;
    step.run({{&s.hull, &s.landscape}}, {{&s.hull, &s.landscape, {{0, 10}}}});
    ASSERT_NE(lookUp(step.records, s.hull, s.landscape), nullptr);
    EXPECT_EQ(lookUp(step.records, s.hull2, s.landscape), nullptr);
    EXPECT_EQ(lookUp(step.records, s.hull, s.box), nullptr);
    // Another proxy with the hull's unique id (the key) but not the recorded one.
    Body impostor{s.hull.object.getCollisionShape(), s.hull.object.getWorldTransform(), s.hull.proxy.m_uniqueId};
    EXPECT_EQ(lookUp(step.records, impostor, s.landscape), nullptr);
    EXPECT_EQ(lookUp(step.records, s.landscape, impostor), nullptr);
    // No wrapper, no object, no proxy.
    bool swapped = false;
    const btCollisionObjectWrapper wl(nullptr, s.landscape.object.getCollisionShape(), &s.landscape.object,
                                      s.landscape.object.getWorldTransform(), -1, -1);
    EXPECT_EQ(step.records.find(nullptr, &wl, swapped), nullptr);
    const btCollisionObjectWrapper noObject(nullptr, s.hull.object.getCollisionShape(), nullptr,
                                            s.hull.object.getWorldTransform(), -1, -1);
    EXPECT_EQ(step.records.find(&noObject, &wl, swapped), nullptr);
    s.hull.object.setBroadphaseHandle(nullptr);
    EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), nullptr);
    s.hull.object.setBroadphaseHandle(&s.hull.proxy);
    EXPECT_NE(lookUp(step.records, s.hull, s.landscape), nullptr);
}

TEST(PairRecords, StaleOnceAShapeOrAWorldTransformChanged) {
    HullOnLandscape s;
    Step step;
    step.run({{&s.hull, &s.landscape}}, {{&s.hull, &s.landscape, {{0, 10}}}});
    const PairTriangles* rec = lookUp(step.records, s.hull, s.landscape);
    ASSERT_NE(rec, nullptr);
    for (Body* moved : {&s.hull, &s.landscape}) {
        // Moved by one bit of one coordinate, in either object.
        const btTransform recorded = moved->object.getWorldTransform();
        btTransform nudged = recorded;
        nudged.getOrigin().setY(std::nextafter(recorded.getOrigin().y(), std::numeric_limits<btScalar>::max()));
        moved->object.setWorldTransform(nudged);
        EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), nullptr);
        EXPECT_EQ(lookUp(step.records, s.landscape, s.hull), nullptr);
        btTransform turned = recorded;
        turned.setRotation(btQuaternion(btVector3(0, 1, 0), btScalar(1e-3)));
        moved->object.setWorldTransform(turned);
        EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), nullptr);
        moved->object.setWorldTransform(recorded);
        EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), rec);
    }
    // Another shape on either object.
    btCollisionShape* hullShape = s.hull.object.getCollisionShape();
    s.hull.object.setCollisionShape(s.hull2.object.getCollisionShape());
    EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), nullptr);
    s.hull.object.setCollisionShape(hullShape);
    btCollisionShape* landscapeShape = s.landscape.object.getCollisionShape();
    s.landscape.object.setCollisionShape(s.box.object.getCollisionShape());
    EXPECT_EQ(lookUp(step.records, s.landscape, s.hull), nullptr);
    s.landscape.object.setCollisionShape(landscapeShape);
    EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), rec);
    // A wrapper (not a child's) whose transform is not the object's, on either side.
    btTransform elsewhere = s.hull.object.getWorldTransform();
    elsewhere.getOrigin() += btVector3(0, btScalar(0.25), 0);
    bool swapped = false;
    const btCollisionObjectWrapper wh(nullptr, hullShape, &s.hull.object, elsewhere, -1, -1);
    const btCollisionObjectWrapper wl(nullptr, landscapeShape, &s.landscape.object,
                                      s.landscape.object.getWorldTransform(), -1, -1);
    EXPECT_EQ(step.records.find(&wh, &wl, swapped), nullptr);
    EXPECT_EQ(step.records.find(&wl, &wh, swapped), nullptr);
}

TEST(PairRecords, ChildWrappersOnlyOnACompoundsSide) {
    ShapeStore shapes;
    btCollisionShape* child = shapes.hull(btVector3(0.4f, 0.3f, 0.3f), 20, 8);
    btCompoundShape compound;
    const btTransform childAt = at(0.2, 0.1, 0);
    compound.addChildShape(childAt, child);
    Body body{&compound, at(0.5, 0.7, 0.5), 4};
    Body landscape{shapes.landscape(8, 1, btScalar(0.3)), at(-4, 0, -4), 8};
    Step step;
    step.run({{&body, &landscape}}, {{&body, &landscape, {{0, 10}, {3, 11}}}});
    const PairTriangles* rec = lookUp(step.records, body, landscape);
    ASSERT_NE(rec, nullptr);
    ASSERT_FALSE(rec->meshTriangles.empty());
    bool swapped = false;
    // The compound algorithm's wrapper of the child: the child's shape at the child's world transform.
    const btTransform childWorld = body.object.getWorldTransform() * childAt;
    const btCollisionObjectWrapper parent(nullptr, &compound, &body.object, body.object.getWorldTransform(), -1, -1);
    const btCollisionObjectWrapper childWrapper(&parent, child, &body.object, childWorld, -1, 0);
    const btCollisionObjectWrapper wl(nullptr, landscape.object.getCollisionShape(), &landscape.object,
                                      landscape.object.getWorldTransform(), -1, -1);
    EXPECT_EQ(step.records.find(&childWrapper, &wl, swapped), rec);
    EXPECT_FALSE(swapped);  // the compound (unique id 4) is the record's first
    EXPECT_EQ(step.records.find(&wl, &childWrapper, swapped), rec);
    EXPECT_TRUE(swapped);
    // Still stale once the compound moved.
    const btTransform recorded = body.object.getWorldTransform();
    body.object.setWorldTransform(at(0.5, 0.8, 0.5));
    EXPECT_EQ(step.records.find(&childWrapper, &wl, swapped), nullptr);
    body.object.setWorldTransform(recorded);
    // A wrapper with another shape on the mesh's side (not a compound) is not trusted.
    const btCollisionObjectWrapper notAChild(nullptr, child, &landscape.object, landscape.object.getWorldTransform(),
                                             -1, 0);
    EXPECT_EQ(step.records.find(&childWrapper, &notAChild, swapped), nullptr);
    EXPECT_EQ(step.records.find(&notAChild, &parent, swapped), nullptr);
}

TEST(PairRecords, ForgottenWithTheirProxyAndAtTheNextStep) {
    HullOnLandscape s;
    Step step;
    step.run({{&s.hull, &s.landscape}, {&s.box, &s.landscape}, {&s.hull, &s.hull2}},
             {{&s.hull, &s.landscape, {{0, 10}}}});
    ASSERT_NE(lookUp(step.records, s.hull, s.landscape), nullptr);
    ASSERT_NE(lookUp(step.records, s.box, s.landscape), nullptr);
    ASSERT_NE(lookUp(step.records, s.hull, s.hull2), nullptr);
    step.records.forgetProxy(&s.hull.proxy);
    EXPECT_EQ(lookUp(step.records, s.hull, s.landscape), nullptr);
    EXPECT_EQ(lookUp(step.records, s.hull2, s.hull), nullptr);
    EXPECT_NE(lookUp(step.records, s.box, s.landscape), nullptr) << "the other pairs' records stay";
    step.records.beginStep(step.number, true);
    EXPECT_EQ(lookUp(step.records, s.box, s.landscape), nullptr) << "a record lives until the next step";
    step.run({{&s.box, &s.landscape}}, {});
    ASSERT_NE(lookUp(step.records, s.box, s.landscape), nullptr);
    step.records.clear();
    EXPECT_EQ(lookUp(step.records, s.box, s.landscape), nullptr);
}

}  // namespace
}  // namespace cullide::test
