#include "narrowphase/AheadPairs.h"

#include "broadphase/PairTriangles.h"
#include "narrowphase/AlgorithmTable.h"

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

namespace cullide::bullet {

namespace {

/// The shape as a btGImpactMeshShape whose parts all have box sets (what the mesh-mesh path reads), or nullptr.
const btGImpactMeshShape* asGImpactMesh(const btCollisionShape* shape) {
    if (shape->getShapeType() != GIMPACT_SHAPE_PROXYTYPE ||
        static_cast<const btGImpactShapeInterface*>(shape)->getGImpactShapeType() != CONST_GIMPACT_TRIMESH_SHAPE)
        return nullptr;
    const auto* mesh = static_cast<const btGImpactMeshShape*>(shape);
    for (int part = 0; part < mesh->getMeshPartCount(); ++part)
        if (!mesh->getMeshPart(part)->hasBoxSet()) return nullptr;
    return mesh;
}

/// The record of the two objects' pair (their own shapes and transforms), or nullptr.
const PairTriangles* recordOf(const NarrowPhaseContext& context, const btCollisionObject& object0,
                              const btCollisionObject& object1) {
    const btCollisionObjectWrapper w0(nullptr, object0.getCollisionShape(), &object0, object0.getWorldTransform(), -1,
                                      -1);
    const btCollisionObjectWrapper w1(nullptr, object1.getCollisionShape(), &object1, object1.getWorldTransform(), -1,
                                      -1);
    bool swapped = false;
    return context.recordFor(&w0, &w1, swapped);
}

/// Whether a GImpact-convex pair of the cache (objects in its order; one shape a btGImpactMeshShape whose parts all
/// have box sets) may be computed ahead: the convex shape's algorithm with a triangle may run on a worker, the pair's
/// algorithm is the dispatcher's GImpact one, and the culler has not proved it out of reach.
bool convexPairAhead(const btCollisionObject& object0, const btCollisionObject& object1, const AheadInputs& in,
                     const NarrowPhaseContext& context) {
    const btCollisionShape& shape0 = *object0.getCollisionShape();
    const btCollisionShape& shape1 = *object1.getCollisionShape();
    const bool convexFirst = shape0.getShapeType() != GIMPACT_SHAPE_PROXYTYPE;
    const btCollisionShape& convex = convexFirst ? shape0 : shape1;
    if (!convex.isConvex() || convex.isCompound() || !objectsMayThread(object0, object1)) return false;
    // The pair's algorithm is this dispatcher's GImpact one (the application registered Bullet's).
    if (!registeredIs<btGImpactCollisionAlgorithm::CreateFunc>(in.funcs[shape0.getShapeType()][shape1.getShapeType()]))
        return false;
    const int triangle = TRIANGLE_SHAPE_PROXYTYPE, convexType = convex.getShapeType();
    const btCollisionAlgorithmCreateFunc* triangleFunc =
        convexFirst ? in.funcs[convexType][triangle] : in.funcs[triangle][convexType];
    if (!convexTriangleThreadable(convex, triangleFunc) || !bullet::pointsIndependentOfManifold(triangleFunc))
        return false;
    if (!in.gimpactConvexCulling) return true;
    // A pair the culler proved out of reach gets no point this step: nothing to compute.
    const PairTriangles* record = recordOf(context, object0, object1);
    return record == nullptr || !record->pruned;
}

}  // namespace

bool listAheadPairs(btOverlappingPairCache& pairCache, const btDispatcherInfo& dispatchInfo, const AheadInputs& in,
                    NarrowPhaseContext& context) {
    bullet::MeshContactBatch& batch = context.meshContacts;
    batch.clear();
    // Only where the dispatch will run the GImpact algorithm's mesh-mesh path: discrete dispatch, Bullet's GImpact
    // algorithm registered (then replaced by the adapter's), more than one thread to use.
    if (in.threads < 2 || dispatchInfo.m_dispatchFunc != btDispatcherInfo::DISPATCH_DISCRETE ||
        !registeredIs<btGImpactCollisionAlgorithm::CreateFunc>(
            in.funcs[GIMPACT_SHAPE_PROXYTYPE][GIMPACT_SHAPE_PROXYTYPE]))
        return false;
    // GImpact-convex pairs: their triangles' algorithms run on the workers, so only with no hook that would see a
    // worker's points, and when the previous step collided enough of their triangles.
    const bool convexAhead = in.lastConvexTriangles >= kMinAheadConvexTriangles && dispatchMayThread(dispatchInfo) &&
                             !dispatchInfo.m_enableSatConvex;
    const int count = pairCache.getNumOverlappingPairs();
    const btBroadphasePair* pairs = count > 0 ? pairCache.getOverlappingPairArrayPtr() : nullptr;
    for (int i = 0; i < count; ++i) {
        const auto* object0 = static_cast<const btCollisionObject*>(pairs[i].m_pProxy0->m_clientObject);
        const auto* object1 = static_cast<const btCollisionObject*>(pairs[i].m_pProxy1->m_clientObject);
        const btGImpactMeshShape* shape0 = asGImpactMesh(object0->getCollisionShape());
        const btGImpactMeshShape* shape1 = asGImpactMesh(object1->getCollisionShape());
        if ((shape0 == nullptr && shape1 == nullptr) || !in.dispatcher.needsCollision(object0, object1)) continue;
        if (shape0 == nullptr || shape1 == nullptr) {
            if (convexAhead && convexPairAhead(*object0, *object1, in, context))
                batch.addConvex(object0, object1, *object0->getCollisionShape(), *object1->getCollisionShape(),
                                object0->getWorldTransform(), object1->getWorldTransform(), in.dispatcher,
                                dispatchInfo);
            continue;
        }
        if (in.gimpactPairCulling) {
            // A culled pair reads the culler's triangle pairs instead, unless its meshes interpenetrate.
            const PairTriangles* record = recordOf(context, *object0, *object1);
            if (record != nullptr && !record->interpenetrating) continue;
        }
        batch.add(object0, object1, *shape0, *shape1, object0->getWorldTransform(), object1->getWorldTransform());
    }
    return batch.size() > 0;
}

}  // namespace cullide::bullet
