#include "narrowphase/GImpactConvexAlgorithm.h"

#include "broadphase/PairTriangles.h"

namespace cullide::bullet {

void GImpactConvexAlgorithm::processCollision(const btCollisionObjectWrapper* body0Wrap,
                                              const btCollisionObjectWrapper* body1Wrap,
                                              const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
    const bool meshFirst = trimeshAgainstConvex(body0Wrap, body1Wrap);
    if ((!meshFirst && !trimeshAgainstConvex(body1Wrap, body0Wrap)) ||
        !shortcutsSound(body0Wrap, body1Wrap, dispatchInfo, *resultOut)) {
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    CullideDispatchStats& stats = m_context.stats;
    bool recordSwapped = false;
    const PairTriangles* verdict = m_context.recordFor(body0Wrap, body1Wrap, recordSwapped);
    beginPair(resultOut, dispatchInfo);
    if (verdict != nullptr && verdict->pruned) {  // the culler proved the pair out of reach: no point this step
        ++stats.clearedPairs;
        return;
    }
    const bool swapped = !meshFirst;
    const btCollisionObjectWrapper* meshWrap = swapped ? body1Wrap : body0Wrap;
    const btCollisionObjectWrapper* convexWrap = swapped ? body0Wrap : body1Wrap;
    const auto* mesh = static_cast<const btGImpactMeshShape*>(meshWrap->getCollisionShape());
    ++stats.convexPairs;
    const bullet::MeshContactBatch::ConvexAhead* ahead = convexAhead(body0Wrap, body1Wrap, dispatchInfo);
    // Computed on the workers for these inputs: the manifold made as Bullet's loop makes it (the dispatcher's
    // getNewManifold), then the points added in Bullet's order, if it has the threshold they were computed with.
    if (ahead != nullptr && ahead->manifold) checkManifold(body0Wrap, body1Wrap);
    if (ahead != nullptr &&
        (!ahead->manifold || getLastManifold()->getContactBreakingThreshold() == ahead->breakingThreshold)) {
        ahead->contacts.forEach([&](const bullet::MeshContact& c) { addContact(body0Wrap, body1Wrap, c); });
        addCounts(ahead->counts);
        ++stats.threadedConvexPairs;
    } else {  // Bullet's loop here (the manifold, if made above, is the one it would make first)
        int& part = swapped ? m_part1 : m_part0;
        for (part = mesh->getMeshPartCount(); part-- > 0;)
            partAgainstConvex(meshWrap, *mesh->getMeshPart(part), convexWrap, swapped);
    }
    finishPair();
}

const bullet::MeshContactBatch::ConvexAhead* GImpactConvexAlgorithm::convexAhead(
    const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
    const btDispatcherInfo& dispatchInfo) const {
    // The ahead loop's result has no closest-point threshold (a dispatch's has none; a query's may).
    if (m_resultOut->m_closestPointDistanceThreshold != 0) return nullptr;
    return m_context.meshContacts.findConvex(body0Wrap->getCollisionObject(), body1Wrap->getCollisionObject(),
                                             body0Wrap->getCollisionShape(), body1Wrap->getCollisionShape(),
                                             body0Wrap->getWorldTransform(), body1Wrap->getWorldTransform(),
                                             dispatchInfo);
}

}  // namespace cullide::bullet
