#include "narrowphase/GImpactConcaveAlgorithm.h"

#include "broadphase/PairTriangles.h"
#include "narrowphase/SurvivingTriangles.h"

#include <BulletCollision/Gimpact/btTriangleShapeEx.h>

namespace cullide::bullet {

/// Bullet's btGImpactTriangleCallback: one triangle of the concave shape, as a triangle shape with the concave shape's
/// margin and its part and index as the shape identifiers of its side, against one GImpact mesh part.
class GImpactConcaveAlgorithm::ConcaveTriangles final : public btTriangleCallback {
public:
    ConcaveTriangles(GImpactConcaveAlgorithm& algorithm, const btCollisionObjectWrapper* gimpactWrap,
                     const btCollisionObjectWrapper* concaveWrap, const btGImpactMeshShapePart& part, btScalar margin,
                     bool swapped)
        : m_algorithm(algorithm), m_gimpactWrap(gimpactWrap), m_concaveWrap(concaveWrap), m_part(part),
          m_margin(margin), m_swapped(swapped) {}

    void processTriangle(btVector3* triangle, int partId, int triangleIndex) override {
        btTriangleShapeEx shape(triangle[0], triangle[1], triangle[2]);
        shape.setMargin(m_margin);
        (m_swapped ? m_algorithm.m_part0 : m_algorithm.m_part1) = partId;
        (m_swapped ? m_algorithm.m_triface0 : m_algorithm.m_triface1) = triangleIndex;
        const btCollisionObjectWrapper wrap(m_concaveWrap, &shape, m_concaveWrap->getCollisionObject(),
                                            m_concaveWrap->getWorldTransform(), partId, triangleIndex);
        const bullet::WrapperInResult in(*m_algorithm.m_resultOut, wrap);
        m_algorithm.partAgainstConvex(m_gimpactWrap, m_part, &wrap, m_swapped);
    }

private:
    GImpactConcaveAlgorithm& m_algorithm;
    const btCollisionObjectWrapper* m_gimpactWrap;
    const btCollisionObjectWrapper* m_concaveWrap;
    const btGImpactMeshShapePart& m_part;
    btScalar m_margin;
    bool m_swapped;
};

namespace {

/// A concave shape this algorithm takes: a triangle mesh, a heightfield, ...; not a plane, not GImpact.
bool concaveNotPlane(const btCollisionShape& shape) {
    return shape.isConcave() && shape.getShapeType() != STATIC_PLANE_PROXYTYPE &&
           shape.getShapeType() != GIMPACT_SHAPE_PROXYTYPE;
}

}  // namespace

void GImpactConcaveAlgorithm::processCollision(const btCollisionObjectWrapper* body0Wrap,
                                               const btCollisionObjectWrapper* body1Wrap,
                                               const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
    const bool gimpactFirst = body0Wrap->getCollisionShape()->getShapeType() == GIMPACT_SHAPE_PROXYTYPE;
    const btCollisionObjectWrapper* gimpactWrap = gimpactFirst ? body0Wrap : body1Wrap;
    const btCollisionObjectWrapper* concaveWrap = gimpactFirst ? body1Wrap : body0Wrap;
    if (gimpactWrap->getCollisionShape()->getShapeType() != GIMPACT_SHAPE_PROXYTYPE ||
        !shortcutsSound(body0Wrap, body1Wrap, dispatchInfo, *resultOut)) {
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    CullideDispatchStats& stats = m_context.stats;
    bool recordSwapped = false;
    const PairTriangles* triangles = m_context.recordFor(body0Wrap, body1Wrap, recordSwapped);
    if (!concaveNotPlane(*concaveWrap->getCollisionShape())) {
        // A compound, a plane against a GImpact compound or lone part, ...: Bullet's algorithm as it is.
        ++stats.fallbackPairs;
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    if (triangles != nullptr) {
        processSurvivors(gimpactWrap, concaveWrap, !gimpactFirst, *triangles, dispatchInfo, resultOut);
    } else if (isGImpactMesh(*gimpactWrap)) {  // not culled (the default): Bullet's contacts
        processWithBulletContacts(gimpactWrap, concaveWrap, !gimpactFirst, dispatchInfo, resultOut);
    } else {
        ++stats.fallbackPairs;
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
    }
}

void GImpactConcaveAlgorithm::processWithBulletContacts(const btCollisionObjectWrapper* gimpactWrap,
                                                        const btCollisionObjectWrapper* concaveWrap, bool swapped,
                                                        const btDispatcherInfo& dispatchInfo,
                                                        btManifoldResult* resultOut) {
    beginPair(resultOut, dispatchInfo);
    ++m_context.stats.concavePairs;
    const auto* gimpact = static_cast<const btGImpactMeshShape*>(gimpactWrap->getCollisionShape());
    const auto* concave = static_cast<const btConcaveShape*>(concaveWrap->getCollisionShape());
    // Bullet's gimpact_vs_concave computes the part's box in the concave shape's frame this way.
    const btTransform gimpactInConcave =
        concaveWrap->getWorldTransform().inverse() * gimpactWrap->getWorldTransform();
    int& part = swapped ? m_part1 : m_part0;
    for (part = gimpact->getMeshPartCount(); part-- > 0;) {
        ConcaveTriangles callback(*this, gimpactWrap, concaveWrap, *gimpact->getMeshPart(part), concave->getMargin(),
                                  swapped);
        btVector3 lo, hi;
        gimpact->getMeshPart(part)->getAabb(gimpactInConcave, lo, hi);
        concave->processAllTriangles(&callback, lo, hi);
    }
    finishPair();
}

void GImpactConcaveAlgorithm::processSurvivors(const btCollisionObjectWrapper* gimpactWrap,
                                               const btCollisionObjectWrapper* concaveWrap, bool swapped,
                                               const PairTriangles& triangles, const btDispatcherInfo& dispatchInfo,
                                               btManifoldResult* resultOut) {
    CullideDispatchStats& stats = m_context.stats;
    ++stats.cullidePairs;
    beginPair(resultOut, dispatchInfo);
    if (triangles.meshTriangles.empty()) {
        ++stats.clearedPairs;
        return;
    }
    stats.trianglePairs += triangles.meshTriangles.size();
    const SurvivingMeshWrapper surviving(concaveWrap, triangles);
    gimpact_vs_shape(gimpactWrap, &surviving.wrapper,
                     static_cast<const btGImpactShapeInterface*>(gimpactWrap->getCollisionShape()), &surviving.shape,
                     swapped);
    finishPair();
}

}  // namespace cullide::bullet
