#include "narrowphase/GImpactPlaneAlgorithm.h"

#include "narrowphase/GImpactPlaneContacts.h"

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>

namespace cullide::bullet {

void GImpactPlaneAlgorithm::processCollision(const btCollisionObjectWrapper* body0Wrap,
                                             const btCollisionObjectWrapper* body1Wrap,
                                             const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
    const bool meshFirst = trimeshAgainstPlane(body0Wrap, body1Wrap);
    if ((!meshFirst && !trimeshAgainstPlane(body1Wrap, body0Wrap)) ||
        !shortcutsSound(body0Wrap, body1Wrap, dispatchInfo, *resultOut)) {
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    beginPair(resultOut, dispatchInfo);
    CullideDispatchStats& stats = m_context.stats;
    ++stats.planePairs;
    const bool swapped = !meshFirst;  // the plane is the pair's first body
    const btCollisionObjectWrapper* gimpactWrap = swapped ? body1Wrap : body0Wrap;
    const btCollisionObjectWrapper* planeWrap = swapped ? body0Wrap : body1Wrap;
    const auto& mesh = *static_cast<const btGImpactMeshShape*>(gimpactWrap->getCollisionShape());
    const auto& plane = *static_cast<const btStaticPlaneShape*>(planeWrap->getCollisionShape());
    const btVector4 equation = bullet::planeEquation(plane, planeWrap->getWorldTransform());
    // Bullet passes the plane's equation itself as the normal (its fourth component, the constant, is kept in the
    // manifold point's normal), or its negation (fourth component 0) for a plane that is the pair's first body.
    const btVector3 flipped = -static_cast<const btVector3&>(equation);
    const btVector3& normal = swapped ? flipped : static_cast<const btVector3&>(equation);
    const bullet::PlanePointSink add = [&](const btVector3& vertex, btScalar distance) {
        addContactPoint(body0Wrap, body1Wrap, vertex, normal, distance);
    };
    bullet::PlaneCounts counts;
    int& part = swapped ? m_part1 : m_part0;
    for (part = mesh.getMeshPartCount(); part--;)
        bullet::planePartContacts(*mesh.getMeshPart(part), gimpactWrap->getWorldTransform(), equation,
                                  plane.getMargin(), add, counts);
    stats.planeVertices += counts.vertices;
    stats.planeVerticesTested += counts.tested;
    finishPair();
}

}  // namespace cullide::bullet
