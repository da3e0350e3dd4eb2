#include "narrowphase/ApartPairs.h"
#include "narrowphase/ThreadedPairs.h"

#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionDispatch/btSphereSphereCollisionAlgorithm.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <BulletCollision/CollisionShapes/btCylinderShape.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>

#include <typeinfo>

namespace cullide::bullet {
namespace {

bool rigidOrPlain(const btCollisionObject& object) {
    const int type = object.getInternalType();
    return type == btCollisionObject::CO_COLLISION_OBJECT || type == btCollisionObject::CO_RIGID_BODY;
}

bool gimpact(const btCollisionObject& object) {
    return object.getCollisionShape()->getShapeType() == GIMPACT_SHAPE_PROXYTYPE;
}

/// A heightfield's box is the height range the application declares, not a bound computed from its data: data above
/// or below it still makes points (Bullet's triangles come from the grid cells under the query box, whatever their
/// heights), so its box proves nothing.
bool boxDeclared(const btCollisionObject& object) {
    return object.getCollisionShape()->getShapeType() == TERRAIN_SHAPE_PROXYTYPE;
}

/// A btCylinderShape (any axis) whose second radial half extent is smaller than the one Bullet's support mapping
/// takes as its radius: the shape reaches beyond its own box along that axis, and Bullet's GJK finds the points
/// there that btDbvtBroadphase's fattened leaves pair.
bool outsideOwnBox(const btCollisionObject& object) {
    const btCollisionShape& shape = *object.getCollisionShape();
    if (shape.getShapeType() != CYLINDER_SHAPE_PROXYTYPE) return false;
    const auto& cylinder = static_cast<const btCylinderShape&>(shape);
    const btVector3 half = cylinder.getHalfExtentsWithoutMargin();
    const int up = cylinder.getUpAxis();
    const int radius = up == 0 ? 1 : 0;  // btCylinderShapeX: y; btCylinderShape (y up) and btCylinderShapeZ: x
    return half[3 - up - radius] < half[radius];
}

/// The pair's box distance, squared, with each box current: an active object's proxy box (the world refreshes it
/// every step), an inactive one's from its shape at its present transform. The world leaves an inactive object's
/// proxy as it was when btCollisionWorld::setForceUpdateAllAabbs(false) is set, and the application may have moved
/// it since (a static platform moved with setWorldTransform alone): Bullet's narrow phase uses the transform.
btScalar currentGapSquared(const btBroadphaseProxy& proxy0, const btCollisionObject& object0,
                           const btBroadphaseProxy& proxy1, const btCollisionObject& object1) {
    btVector3 min0 = proxy0.m_aabbMin, max0 = proxy0.m_aabbMax, min1 = proxy1.m_aabbMin, max1 = proxy1.m_aabbMax;
    if (!object0.isActive()) object0.getCollisionShape()->getAabb(object0.getWorldTransform(), min0, max0);
    if (!object1.isActive()) object1.getCollisionShape()->getAabb(object1.getWorldTransform(), min1, max1);
    return boxDistanceSquared(min0, max0, min1, max1);
}

/// What the pair's algorithm does to its manifolds in a run that finds no point: btSphereSphereCollisionAlgorithm
/// clears its manifold (Bullet builds it with CLEAR_MANIFOLD); every other algorithm that may be skipped refreshes
/// it at the end of its run (btManifoldResult::refreshContactPoints: each point moved with the two objects, then
/// dropped when its distance along the normal exceeds the manifold's threshold or it drifted sideways by more).
/// A refresh keeps a point whose objects went through each other along its normal (a negative distance, little
/// drift: a fast body through a thin plate, a trigger falling through a trigger), so such a point stays, as in
/// Bullet.
void finishAsBullet(const btCollisionAlgorithm& algorithm, btManifoldArray& manifolds) {
    const bool clears = typeid(algorithm) == typeid(btSphereSphereCollisionAlgorithm);
    for (int i = 0; i < manifolds.size(); ++i) {
        btPersistentManifold& m = *manifolds[i];
        if (m.getNumContacts() == 0) continue;
        if (clears)
            m.clearManifold();
        else  // the objects' transforms in the manifold's own order, as btManifoldResult picks them
            m.refreshContactPoints(m.getBody0()->getWorldTransform(), m.getBody1()->getWorldTransform());
    }
}

}  // namespace

btScalar boxDistanceSquared(const btVector3& min0, const btVector3& max0, const btVector3& min1,
                            const btVector3& max1) {
    btScalar sum = 0;
    for (int a = 0; a < 3; ++a) {
        const btScalar gap = btMax(min1[a] - max0[a], min0[a] - max1[a]);
        if (gap > 0) sum += gap * gap;
    }
    return sum;
}

btScalar manifoldBreakingThreshold(const btCollisionDispatcher& dispatcher, const btCollisionObject& object0,
                                   const btCollisionObject& object1) {
    if ((dispatcher.getDispatcherFlags() & btCollisionDispatcher::CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD) == 0)
        return gContactBreakingThreshold;
    return btMin(object0.getCollisionShape()->getContactBreakingThreshold(gContactBreakingThreshold),
                 object1.getCollisionShape()->getContactBreakingThreshold(gContactBreakingThreshold));
}

bool skipIfApart(btBroadphasePair& pair, btCollisionDispatcher& dispatcher, btManifoldArray& scratch) {
    if (pair.m_algorithm == nullptr) return false;  // first dispatch of the pair: made as Bullet makes it
    const btBroadphaseProxy& proxy0 = *pair.m_pProxy0;
    const btBroadphaseProxy& proxy1 = *pair.m_pProxy1;
    const auto* object0 = static_cast<const btCollisionObject*>(proxy0.m_clientObject);
    const auto* object1 = static_cast<const btCollisionObject*>(proxy1.m_clientObject);
    // Two objects at rest: the dispatch does not collide them (needsCollision), so their pair is Bullet's to skip,
    // at the cost Bullet's own loop pays for it.
    if (object0 == nullptr || object1 == nullptr || (!object0->isActive() && !object1->isActive())) return false;
    // Overlapping (or NaN) proxy boxes: the algorithm decides. Most pairs end here, before any other test.
    if (!(boxDistanceSquared(proxy0.m_aabbMin, proxy0.m_aabbMax, proxy1.m_aabbMin, proxy1.m_aabbMax) > 0))
        return false;
    if (!rigidOrPlain(*object0) || !rigidOrPlain(*object1) ||
        gimpact(*object0) || gimpact(*object1) || boxDeclared(*object0) || boxDeclared(*object1) ||
        outsideOwnBox(*object0) || outsideOwnBox(*object1) ||
        !dispatcher.needsCollision(object0, object1) || !freesNoManifoldWhenApart(*pair.m_algorithm))
        return false;
    const btScalar gap2 = currentGapSquared(proxy0, *object0, proxy1, *object1);
    const btScalar t = manifoldBreakingThreshold(dispatcher, *object0, *object1);
    if (!(t >= 0 && gap2 > t * t)) return false;
    scratch.resize(0);
    pair.m_algorithm->getAllContactManifolds(scratch);
    for (int i = 0; i < scratch.size(); ++i) {  // a manifold made with a larger threshold (a custom getNewManifold)
        const btScalar own = scratch[i]->getContactBreakingThreshold();
        if (!(gap2 > own * own)) return false;
    }
    finishAsBullet(*pair.m_algorithm, scratch);
    return true;
}

}  // namespace cullide::bullet
