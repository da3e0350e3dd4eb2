#include "narrowphase/ConvexMeshAlgorithm.h"

#include "broadphase/PairTriangles.h"
#include "narrowphase/SurvivingTriangles.h"
#include "narrowphase/WorldResult.h"

namespace cullide::bullet {

template <bool MeshFirst>
void ConvexMeshAlgorithm<MeshFirst>::processCollision(const btCollisionObjectWrapper* body0Wrap,
                                                      const btCollisionObjectWrapper* body1Wrap,
                                                      const btDispatcherInfo& dispatchInfo,
                                                      btManifoldResult* resultOut) {
    CullideDispatchStats& stats = m_context.stats;
    bool swapped = false;
    const PairTriangles* triangles = m_context.recordFor(body0Wrap, body1Wrap, swapped);
    const btCollisionObjectWrapper* meshWrap = MeshFirst ? body0Wrap : body1Wrap;
    if (triangles == nullptr || !meshWrap->getCollisionShape()->isConcave() || !thresholdChecked(*resultOut)) {
        ++stats.fallbackPairs;
        btConvexConcaveCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    ++stats.cullidePairs;
    if (triangles->meshTriangles.empty()) {
        ++stats.clearedPairs;
        btManifoldArray manifolds;
        getAllContactManifolds(manifolds);
        for (int i = 0; i < manifolds.size(); ++i) m_dispatcher->clearManifold(manifolds[i]);
        return;
    }
    stats.trianglePairs += triangles->meshTriangles.size();
    const SurvivingMeshWrapper surviving(meshWrap, *triangles);
    const btCollisionObjectWrapper* mesh = &surviving.wrapper;
    btConvexConcaveCollisionAlgorithm::processCollision(MeshFirst ? mesh : body0Wrap, MeshFirst ? body1Wrap : mesh,
                                                        dispatchInfo, resultOut);
}

template class ConvexMeshAlgorithm<false>;
template class ConvexMeshAlgorithm<true>;

}  // namespace cullide::bullet
