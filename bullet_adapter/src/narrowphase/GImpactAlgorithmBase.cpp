#include "narrowphase/GImpactAlgorithmBase.h"

#include "narrowphase/WorldResult.h"

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

namespace cullide::bullet {

namespace {
thread_local btAlignedObjectArray<int> t_candidates;  // Bullet's box query of one mesh part
}  // namespace

bool GImpactAlgorithmBase::isGImpactMesh(const btCollisionObjectWrapper& w) {
    const btCollisionShape* shape = w.getCollisionShape();
    return shape->getShapeType() == GIMPACT_SHAPE_PROXYTYPE &&
           static_cast<const btGImpactShapeInterface*>(shape)->getGImpactShapeType() == CONST_GIMPACT_TRIMESH_SHAPE;
}

bool GImpactAlgorithmBase::trimeshAgainstConvex(const btCollisionObjectWrapper* mesh,
                                                const btCollisionObjectWrapper* convex) {
    const btCollisionShape* c = convex->getCollisionShape();
    return isGImpactMesh(*mesh) && c->isConvex() && !c->isCompound();
}

bool GImpactAlgorithmBase::trimeshAgainstPlane(const btCollisionObjectWrapper* mesh,
                                               const btCollisionObjectWrapper* plane) {
#ifdef GIMPACT_VS_PLANE_COLLISION
    return isGImpactMesh(*mesh) && plane->getCollisionShape()->getShapeType() == STATIC_PLANE_PROXYTYPE;
#else
    (void)mesh;
    (void)plane;
    return false;
#endif
}

bool GImpactAlgorithmBase::shortcutsSound(const btCollisionObjectWrapper* body0Wrap,
                                          const btCollisionObjectWrapper* body1Wrap,
                                          const btDispatcherInfo& dispatchInfo, const btManifoldResult& resultOut) {
    if (!thresholdChecked(resultOut)) return false;
    if (!dispatchInfo.m_enableSatConvex) return true;
    const bool meshPair = isGImpactMesh(*body0Wrap) && isGImpactMesh(*body1Wrap);
    return meshPair || trimeshAgainstPlane(body0Wrap, body1Wrap) || trimeshAgainstPlane(body1Wrap, body0Wrap);
}

void GImpactAlgorithmBase::addContacts(const btCollisionObjectWrapper* body0Wrap,
                                       const btCollisionObjectWrapper* body1Wrap,
                                       const std::vector<bullet::MeshContact>& points) {
    for (const bullet::MeshContact& c : points) addContact(body0Wrap, body1Wrap, c);
}

void GImpactAlgorithmBase::addContact(const btCollisionObjectWrapper* body0Wrap,
                                      const btCollisionObjectWrapper* body1Wrap, const bullet::MeshContact& c) {
    m_part0 = c.part0;
    m_triface0 = c.face0;
    m_part1 = c.part1;
    m_triface1 = c.face1;
    addContactPoint(body0Wrap, body1Wrap, c.point, c.normal, c.distance);
}

void GImpactAlgorithmBase::partAgainstConvex(const btCollisionObjectWrapper* meshWrap,
                                             const btGImpactMeshShapePart& meshPart,
                                             const btCollisionObjectWrapper* convexWrap, bool swapped) {
    const btCollisionShape* convex = convexWrap->getCollisionShape();
    btAlignedObjectArray<int>& candidates = t_candidates;
    candidates.resize(0);
    if (meshPart.hasBoxSet())
        bullet::convexCandidates(meshWrap->getWorldTransform(), meshPart, *convex, convexWrap->getWorldTransform(),
                                 candidates);
    else
        gimpact_vs_shape_find_pairs(meshWrap->getWorldTransform(), convexWrap->getWorldTransform(), &meshPart, convex,
                                    candidates);
    if (candidates.size() == 0) return;
    // Bullet's loop makes the pair's manifold with its first candidate's algorithm (newAlgorithm's checkManifold,
    // bodies in the order the algorithm gets them), whether a point follows or not: so does this one, also when
    // every candidate is skipped, so that the dispatcher's manifolds (empty ones too, which the solver's island
    // sort sees) stay Bullet's.
    checkManifold(swapped ? convexWrap : meshWrap, swapped ? meshWrap : convexWrap);
    const bullet::ConvexTarget target{m_dispatcher, getLastManifold(), m_resultOut, m_dispatchInfo};
    bullet::ConvexCounts counts;
    meshPart.lockChildShapes();
    bullet::collideCandidates({meshWrap, convexWrap, swapped}, meshPart, &candidates[0], candidates.size(),
                              {m_part0, m_triface0, m_part1, m_triface1}, target, counts);
    meshPart.unlockChildShapes();
    addCounts(counts);
}

void GImpactAlgorithmBase::addCounts(const bullet::ConvexCounts& counts) {
    m_context.stats.convexCandidates += counts.candidates;
    m_context.stats.convexTriangles += counts.triangles;
    m_context.stats.convexUnchecked += counts.unchecked;
}

}  // namespace cullide::bullet
