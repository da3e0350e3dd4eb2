#include "narrowphase/AlgorithmTable.h"

#include "broadphase/ShapeGeometry.h"

#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>

namespace cullide::bullet {

namespace {

/// Whether the broadphase culls the wrapped convex shape as triangles: a convex hull body, or a convex child of a
/// compound (the compound algorithm wraps its children; the compound is culled as its children's hulls and boxes).
bool culledConvex(const btCollisionObjectWrapper* w) {
    const btCollisionShape* shape = w->getCollisionShape();
    if (shape->getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE) return true;
    const btCollisionObject* object = w->getCollisionObject();
    return shape->isConvex() && object != nullptr && object->getCollisionShape() != shape &&
           object->getCollisionShape()->getShapeType() == COMPOUND_SHAPE_PROXYTYPE;
}

/// A concave shape other than a plane, which Bullet's GImpact algorithm collides with the mesh's vertices.
bool concaveNotPlane(int shapeType) {
    return btBroadphaseProxy::isConcave(shapeType) && shapeType != STATIC_PLANE_PROXYTYPE;
}

}  // namespace

AlgorithmTable::AlgorithmTable(NarrowPhaseContext& context)
    : m_gimpactGImpact(context),
      m_gimpactConcave(context),
      m_gimpactConvex(context),
      m_gimpactPlane(context),
      m_convexMesh(context),
      m_meshConvex(context),
      m_entries{&m_gimpactGImpact, &m_gimpactConcave, &m_gimpactConvex, &m_gimpactPlane, &m_convexMesh,
                &m_meshConvex} {}

AlgorithmTable::Kind AlgorithmTable::kindOf(const btCollisionObjectWrapper* body0Wrap,
                                            const btCollisionObjectWrapper* body1Wrap,
                                            const btCollisionAlgorithmCreateFunc* registered,
                                            const CullideBroadphase& broadphase) {
    const int t0 = body0Wrap->getCollisionShape()->getShapeType();
    const int t1 = body1Wrap->getCollisionShape()->getShapeType();
    const bool gimpact = t0 == GIMPACT_SHAPE_PROXYTYPE || t1 == GIMPACT_SHAPE_PROXYTYPE;
    const bool convexMesh = isTriangleMeshType(t0) || isTriangleMeshType(t1);
    // Most lookups come from a per-triangle loop (a GImpact triangle or a mesh triangle against a convex shape):
    // neither kind, and answered here.
    if (!gimpact && !convexMesh) return Kind::None;
    if (gimpact && registeredIs<btGImpactCollisionAlgorithm::CreateFunc>(registered)) {
        if (t0 == GIMPACT_SHAPE_PROXYTYPE && t1 == GIMPACT_SHAPE_PROXYTYPE) return Kind::GImpactGImpact;
        if ((t0 == GIMPACT_SHAPE_PROXYTYPE && concaveNotPlane(t1)) || (concaveNotPlane(t0) && t1 == GIMPACT_SHAPE_PROXYTYPE))
            return Kind::GImpactConcave;
        if (GImpactAlgorithmBase::trimeshAgainstConvex(body0Wrap, body1Wrap) ||
            GImpactAlgorithmBase::trimeshAgainstConvex(body1Wrap, body0Wrap))
            return Kind::GImpactConvex;
        if (GImpactAlgorithmBase::trimeshAgainstPlane(body0Wrap, body1Wrap) ||
            GImpactAlgorithmBase::trimeshAgainstPlane(body1Wrap, body0Wrap))
            return Kind::GImpactPlane;
    }
    // Convex-mesh pairs read the culler's triangles only with convex-mesh culling on; otherwise Bullet's own
    // algorithm runs them without a record lookup per pair and step.
    if (!convexMesh || !broadphase.mayCull(CulledKind::ConvexMesh)) return Kind::None;
    if (isTriangleMeshType(t1) && culledConvex(body0Wrap) &&
        registeredIs<btConvexConcaveCollisionAlgorithm::CreateFunc>(registered))
        return Kind::ConvexMesh;
    if (isTriangleMeshType(t0) && culledConvex(body1Wrap) &&
        registeredIs<btConvexConcaveCollisionAlgorithm::SwappedCreateFunc>(registered))
        return Kind::MeshConvex;
    return Kind::None;
}

btCollisionAlgorithmCreateFunc* AlgorithmTable::replacementFor(const btCollisionObjectWrapper* body0Wrap,
                                                               const btCollisionObjectWrapper* body1Wrap,
                                                               const btCollisionAlgorithmCreateFunc* registered,
                                                               const CullideBroadphase& broadphase) {
    const Kind kind = kindOf(body0Wrap, body1Wrap, registered, broadphase);
    return kind == Kind::None ? nullptr : m_entries[static_cast<std::size_t>(kind)];
}

}  // namespace cullide::bullet
