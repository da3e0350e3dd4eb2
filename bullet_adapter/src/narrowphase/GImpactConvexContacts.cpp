#include "narrowphase/GImpactConvexContacts.h"

#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btConvexConvexAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btSphereTriangleCollisionAlgorithm.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>

#include <typeinfo>

namespace cullide::bullet {
namespace {

/// Safety factor on the reach: GJK's and the polyhedral clipper's tolerances are far below it.
constexpr btScalar kConvexReachFactor = btScalar(1.5);

btScalar largestCoordinate(const btVector3& v) {
    const btVector3 a = v.absolute();
    return a[a.maxAxis()];
}

/// How far outside the convex shape's box a triangle with margin `margin` can still make a point: factor * (the
/// margin + the breaking threshold), plus the float slack of the mapped coordinates.
btScalar reachDistance(const ConvexReach& reach, btScalar margin) {
    return kConvexReachFactor * (margin + reach.threshold) + reach.slack;
}

/// A result that records each point as the pair's result would receive it: the arguments and the shape identifiers
/// set at the time.
class RecordingResult final : public btManifoldResult {
public:
    RecordingResult(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                    std::vector<MeshContact>& out)
        : btManifoldResult(body0Wrap, body1Wrap), m_out(out) {}

    void addContactPoint(const btVector3& normalOnBInWorld, const btVector3& pointInWorld, btScalar depth) override {
        m_out.push_back({pointInWorld, normalOnBInWorld, depth, m_partId0, m_index0, m_partId1, m_index1});
    }

private:
    std::vector<MeshContact>& m_out;
};

}  // namespace

/// btManifoldResult drops a point deeper than the manifold's contact breaking threshold (depth measured between the
/// margin-inflated shapes), and btCollisionDispatcher::getNewManifold sets that threshold to
/// gContactBreakingThreshold, scaled by the smaller angular motion disc of the two objects' shapes when
/// CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD is set; the larger of the two rules is used here, whatever the flag.
ConvexReach convexReach(const btCollisionObjectWrapper& meshWrap, const btCollisionObjectWrapper& convexWrap) {
    ConvexReach reach;
    reach.meshToConvex = convexWrap.getWorldTransform().inverseTimes(meshWrap.getWorldTransform());
    convexWrap.getCollisionShape()->getAabb(btTransform::getIdentity(), reach.min, reach.max);
    const btCollisionShape* meshShape = meshWrap.getCollisionObject()->getCollisionShape();
    const btCollisionShape* convexShape = convexWrap.getCollisionObject()->getCollisionShape();
    reach.threshold = btMax(gContactBreakingThreshold,
                            btMin(meshShape->getContactBreakingThreshold(gContactBreakingThreshold),
                                  convexShape->getContactBreakingThreshold(gContactBreakingThreshold)));
    const btScalar scale = btMax(btMax(largestCoordinate(reach.min), largestCoordinate(reach.max)),
                                 largestCoordinate(reach.meshToConvex.getOrigin()));
    reach.slack = 64 * SIMD_EPSILON * scale;
    return reach;
}

/// (Separating-plane tests for triangle against triangle, tried: they skipped ~8 % more GImpact-concave candidates,
/// but with double-precision Bullet 5 of 108,081 contact keys of a heightfield scene went missing, not explained;
/// without them none does. Only the box test is used.)
bool convexCanTouch(const btTriangleShapeEx& triangle, const ConvexReach& reach) {
    btVector3 lo = reach.meshToConvex(triangle.m_vertices1[0]);
    btVector3 hi = lo;
    for (int k = 1; k < 3; ++k) {
        const btVector3 v = reach.meshToConvex(triangle.m_vertices1[k]);
        lo.setMin(v);
        hi.setMax(v);
    }
    // The margin as the virtual getMargin gives it (btTriangleShapeEx does not override it), without the call.
    const btScalar d = reachDistance(reach, triangle.btConvexInternalShape::getMargin());
    for (int k = 0; k < 3; ++k)
        if (lo[k] > reach.max[k] + d || hi[k] < reach.min[k] - d) return false;
    return true;
}

/// The part's box (Bullet's, margin included), mapped into the convex shape's frame, inside the convex shape's box
/// grown by reachDistance at the part's margin: in a world of small units Bullet's absolute contact breaking
/// threshold (0.02) alone can reach across whole objects. A part's box stale or wrong by rounding only makes the
/// loop run GJK on a candidate convexCanTouch would have skipped: Bullet's own loop runs them all.
bool partWithinReach(const btGImpactMeshShapePart& part, const ConvexReach& reach) {
    btVector3 lo, hi;
    part.getAabb(reach.meshToConvex, lo, hi);
    const btScalar d = reachDistance(reach, part.getMargin());
    for (int k = 0; k < 3; ++k)
        if (!(lo[k] >= reach.min[k] - d && hi[k] <= reach.max[k] + d)) return false;
    return true;
}

void convexCandidates(const btTransform& meshTransform, const btGImpactMeshShapePart& part,
                      const btCollisionShape& convex, const btTransform& convexTransform,
                      btAlignedObjectArray<int>& out) {
    // The convex shape's box in the part's frame, the transform composed as Bullet's query composes it.
    btTransform convexInMesh = meshTransform.inverse();
    convexInMesh *= convexTransform;
    btAABB box;
    convex.getAabb(convexInMesh, box.m_min, box.m_max);
    part.getBoxSet()->boxQuery(box, out);
}

void collideCandidates(const ConvexSides& sides, const btGImpactMeshShapePart& part, const int* candidates, int count,
                       ShapeIds ids, const ConvexTarget& target, ConvexCounts& counts) {
    const ConvexReach reach = convexReach(*sides.mesh, *sides.convex);
    const bool allWithinReach = partWithinReach(part, reach);
    if (allWithinReach) counts.unchecked += static_cast<std::size_t>(count);
    int& face = sides.convexFirst ? ids.face1 : ids.face0;
    btTriangleShapeEx triangle;
    for (int i = count; i-- > 0;) {
        face = candidates[i];
        part.getBulletTriangle(candidates[i], triangle);
        ++counts.candidates;
        if (!allWithinReach && !convexCanTouch(triangle, reach)) continue;
        ++counts.triangles;
        // The wrapper carries the first body's identifiers whichever side the mesh is, as Bullet's loop does.
        const btCollisionObjectWrapper triangleWrap(sides.mesh, &triangle, sides.mesh->getCollisionObject(),
                                                    sides.mesh->getWorldTransform(), ids.part0, ids.face0);
        const WrapperInResult in(*target.result, triangleWrap);
        const btCollisionObjectWrapper* first = sides.convexFirst ? sides.convex : &triangleWrap;
        const btCollisionObjectWrapper* second = sides.convexFirst ? &triangleWrap : sides.convex;
        btCollisionAlgorithm* algorithm =
            target.dispatcher->findAlgorithm(first, second, target.manifold, BT_CONTACT_POINT_ALGORITHMS);
        target.result->setShapeIdentifiersA(ids.part0, ids.face0);
        target.result->setShapeIdentifiersB(ids.part1, ids.face1);
        algorithm->processCollision(first, second, *target.info, target.result);
        algorithm->~btCollisionAlgorithm();
        target.dispatcher->freeCollisionAlgorithm(algorithm);
    }
}

bool pointsIndependentOfManifold(const btCollisionAlgorithmCreateFunc* triangleFunc) {
    if (triangleFunc == nullptr) return false;
    if (typeid(*triangleFunc) == typeid(btSphereTriangleCollisionAlgorithm::CreateFunc)) return true;
    return typeid(*triangleFunc) == typeid(btConvexConvexAlgorithm::CreateFunc) &&
           static_cast<const btConvexConvexAlgorithm::CreateFunc*>(triangleFunc)->m_numPerturbationIterations == 0;
}

void convexChunkContacts(const ConvexSides& sides, int partIndex, const int* candidates, int count,
                         btScalar breakingThreshold, btCollisionDispatcher& dispatcher, const btDispatcherInfo& info,
                         std::vector<MeshContact>& out, ConvexCounts& counts) {
    const bullet::PairThreadScope onPairThread;  // the triangles' algorithms come from the heap, not the pool
    const btCollisionObjectWrapper* body0 = sides.convexFirst ? sides.convex : sides.mesh;
    const btCollisionObjectWrapper* body1 = sides.convexFirst ? sides.mesh : sides.convex;
    const btCollisionObject* object0 = body0->getCollisionObject();
    const btCollisionObject* object1 = body1->getCollisionObject();
    // The pair's bodies and breaking threshold: all the algorithms read of their manifold.
    btPersistentManifold manifold(object0, object1, 0, breakingThreshold, breakingThreshold);
    RecordingResult result(body0, body1, out);
    result.setPersistentManifold(&manifold);
    ShapeIds ids;
    (sides.convexFirst ? ids.part1 : ids.part0) = partIndex;
    const auto* mesh = static_cast<const btGImpactMeshShape*>(sides.mesh->getCollisionShape());
    collideCandidates(sides, *mesh->getMeshPart(partIndex), candidates, count, ids,
                      {&dispatcher, &manifold, &result, &info}, counts);
}

WrapperInResult::WrapperInResult(btManifoldResult& result, const btCollisionObjectWrapper& wrap)
    : m_result(result),
      m_first(result.getBody0Wrap()->getCollisionObject() == wrap.getCollisionObject()),
      m_previous(m_first ? result.getBody0Wrap() : result.getBody1Wrap()) {
    if (m_first)
        m_result.setBody0Wrap(&wrap);
    else
        m_result.setBody1Wrap(&wrap);
}

WrapperInResult::~WrapperInResult() {
    if (m_first)
        m_result.setBody0Wrap(m_previous);
    else
        m_result.setBody1Wrap(m_previous);
}

}  // namespace cullide::bullet
