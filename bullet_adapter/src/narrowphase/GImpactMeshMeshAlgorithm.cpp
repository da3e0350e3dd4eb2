#include "narrowphase/GImpactMeshMeshAlgorithm.h"

#include "broadphase/PairTriangles.h"

#include <algorithm>
#include <array>
#include <vector>

namespace cullide::bullet {

namespace {

thread_local std::vector<std::array<int, 4>> t_ordered;  // part0, part1, tri0, tri1
thread_local std::vector<bullet::MeshContact> t_contacts;
thread_local std::vector<int> t_interleaved;

bool allPartsHaveBoxSets(const btGImpactMeshShape& shape) {
    for (int part = 0; part < shape.getMeshPartCount(); ++part)
        if (!shape.getMeshPart(part)->hasBoxSet()) return false;
    return true;
}

/// Keeps, of pairs[begin, end) (one part pair), the triangle pairs that Bullet's own candidate search
/// (btGImpactQuantizedBvh::find_collision) would also produce, into `interleaved`: the parts' quantized leaf boxes
/// overlap in part 0's frame, tested as Bullet tests them (the 15-axis test for the roots, the 6 face axes below).
/// CULLIDE's pairs are near pairs; Bullet's are box-overlapping pairs; the clip method runs on pairs in both. Both
/// parts have box sets.
void bulletCandidates(const btTransform& trans0, const btGImpactMeshShapePart& part0, const btTransform& trans1,
                      const btGImpactMeshShapePart& part1, GImpactLeafIndex& leafIndex,
                      const std::vector<std::array<int, 4>>& pairs, std::size_t begin, std::size_t end,
                      std::vector<int>& interleaved) {
    interleaved.clear();
    const btGImpactBoxSet& set0 = *part0.getBoxSet();
    const btGImpactBoxSet& set1 = *part1.getBoxSet();
    BT_BOX_BOX_TRANSFORM_CACHE cache;
    cache.calc_from_homogenic(trans0, trans1);
    btAABB box0, box1;
    set0.getNodeBound(0, box0);
    set1.getNodeBound(0, box1);
    if (!box0.overlapping_trans_cache(box1, cache, true)) return;  // Bullet finds no pair at all
    const bool rootsOnly = set0.isLeafNode(0) && set1.isLeafNode(0);
    std::vector<int>& leaves0 = leafIndex.leavesOf(set0);
    std::vector<int>& leaves1 = &set1 == &set0 ? leaves0 : leafIndex.leavesOf(set1);
    for (std::size_t i = begin; i < end; ++i) {
        const int leaf0 = GImpactLeafIndex::leafOf(set0, leaves0, pairs[i][2]);
        const int leaf1 = GImpactLeafIndex::leafOf(set1, leaves1, pairs[i][3]);
        if (leaf0 < 0 || leaf1 < 0) continue;  // not in Bullet's box set: Bullet never tests it either
        if (!rootsOnly) {
            set0.getNodeBound(leaf0, box0);
            set1.getNodeBound(leaf1, box1);
            if (!box0.overlapping_trans_cache(box1, cache, false)) continue;
        }
        interleaved.push_back(pairs[i][2]);
        interleaved.push_back(pairs[i][3]);
    }
}

}  // namespace

void GImpactMeshMeshAlgorithm::processCollision(const btCollisionObjectWrapper* body0Wrap,
                                                const btCollisionObjectWrapper* body1Wrap,
                                                const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
    if (!isGImpactMesh(*body0Wrap) || !isGImpactMesh(*body1Wrap) ||
        !shortcutsSound(body0Wrap, body1Wrap, dispatchInfo, *resultOut)) {
        // A btGImpactCompoundShape, a btGImpactMeshShapePart used on its own, a result that keeps points beyond the
        // breaking threshold: Bullet's algorithm as it is.
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    CullideDispatchStats& stats = m_context.stats;
    bool swapped = false;
    const PairTriangles* triangles = m_context.recordFor(body0Wrap, body1Wrap, swapped);
    const auto& shape0 = *static_cast<const btGImpactMeshShape*>(body0Wrap->getCollisionShape());
    const auto& shape1 = *static_cast<const btGImpactMeshShape*>(body1Wrap->getCollisionShape());
    if (!allPartsHaveBoxSets(shape0) || !allPartsHaveBoxSets(shape1)) {
        // A part without a box set: Bullet then tests child boxes; let it.
        ++stats.fallbackPairs;
        processAsBulletDoes(body0Wrap, body1Wrap, dispatchInfo, resultOut);
        return;
    }
    if (triangles == nullptr) {  // not culled (the default for GImpact-GImpact): Bullet's contacts
        ++stats.fallbackPairs;
        processWithBulletContacts(body0Wrap, body1Wrap, shape0, shape1, dispatchInfo, resultOut);
        return;
    }
    ++stats.cullidePairs;
    if (triangles->interpenetrating) {
        // The meshes intersect: GImpact's penetration contacts can come from triangle pairs far apart, which
        // CULLIDE's near pairs do not include. Bullet's contacts are kept (the fallback is optional).
        ++stats.penetrationPairs;
        processWithBulletContacts(body0Wrap, body1Wrap, shape0, shape1, dispatchInfo, resultOut);
        return;
    }
    beginPair(resultOut, dispatchInfo);
    if (!triangles->pairs.empty()) processSurvivors(body0Wrap, body1Wrap, shape0, shape1, *triangles, swapped);
    if (getLastManifold() != nullptr && getLastManifold()->getNumContacts() > 0) {
        m_resultOut->refreshContactPoints();
        return;
    }
    // No point from the kept triangles: Bullet's clip method may still make one from a triangle behind the other
    // within their overlapping boxes (CullingPolicy.h, pairReach), which only Bullet's own search finds. Its
    // contacts, then: a pair Bullet gives a point never goes without one. (Mostly a pair whose root boxes are apart,
    // where the search ends at once.)
    ++stats.clearedPairs;
    processWithBulletContacts(body0Wrap, body1Wrap, shape0, shape1, dispatchInfo, resultOut);
}

void GImpactMeshMeshAlgorithm::processSurvivors(const btCollisionObjectWrapper* body0Wrap,
                                                const btCollisionObjectWrapper* body1Wrap,
                                                const btGImpactMeshShape& shape0, const btGImpactMeshShape& shape1,
                                                const PairTriangles& triangles, bool swapped) {
    // Pairs in (body0, body1) order, grouped by part pair, deterministic order.
    std::vector<std::array<int, 4>>& ordered = t_ordered;
    ordered.clear();
    for (const BulletTrianglePair& p : triangles.pairs) {
        const BulletTriangle& t0 = swapped ? p.b : p.a;
        const BulletTriangle& t1 = swapped ? p.a : p.b;
        ordered.push_back({t0.part, t1.part, t0.index, t1.index});
    }
    if (swapped) std::sort(ordered.begin(), ordered.end());

    std::vector<int>& interleaved = t_interleaved;
    std::size_t begin = 0;
    while (begin < ordered.size()) {
        std::size_t end = begin;
        while (end < ordered.size() && ordered[end][0] == ordered[begin][0] && ordered[end][1] == ordered[begin][1])
            ++end;
        m_part0 = ordered[begin][0];
        m_part1 = ordered[begin][1];
        const btGImpactMeshShapePart* part0 = shape0.getMeshPart(m_part0);
        const btGImpactMeshShapePart* part1 = shape1.getMeshPart(m_part1);
        bulletCandidates(body0Wrap->getWorldTransform(), *part0, body1Wrap->getWorldTransform(), *part1,
                         m_context.leafIndex, ordered, begin, end, interleaved);
        m_context.stats.trianglePairs += interleaved.size() / 2;
        if (!interleaved.empty()) {
            const bullet::PartPair parts{part0, part1, m_part0, m_part1, &body0Wrap->getWorldTransform(),
                                         &body1Wrap->getWorldTransform()};
            bullet::MeshContactScratch& scratch = bullet::threadScratch();
            scratch.world0.begin(*part0, body0Wrap->getWorldTransform());
            scratch.world1.begin(*part1, body1Wrap->getWorldTransform());
            std::vector<bullet::MeshContact>& contacts = t_contacts;
            contacts.clear();
            part0->lockChildShapes();
            part1->lockChildShapes();
            bullet::triangleContacts(parts, interleaved, scratch.world0, scratch.world1, contacts);
            part1->unlockChildShapes();
            part0->unlockChildShapes();
            addContacts(body0Wrap, body1Wrap, contacts);
        }
        begin = end;
    }
}

void GImpactMeshMeshAlgorithm::processWithBulletContacts(const btCollisionObjectWrapper* body0Wrap,
                                                         const btCollisionObjectWrapper* body1Wrap,
                                                         const btGImpactMeshShape& shape0,
                                                         const btGImpactMeshShape& shape1,
                                                         const btDispatcherInfo& dispatchInfo,
                                                         btManifoldResult* resultOut) {
    beginPair(resultOut, dispatchInfo);
    const btTransform& trans0 = body0Wrap->getWorldTransform();
    const btTransform& trans1 = body1Wrap->getWorldTransform();
    const bullet::ContactLists* ahead = m_context.meshContacts.find(
        body0Wrap->getCollisionObject(), body1Wrap->getCollisionObject(), &shape0, &shape1, trans0, trans1);
    if (ahead != nullptr) {
        ahead->forEach([&](const bullet::MeshContact& c) { addContact(body0Wrap, body1Wrap, c); });
    } else {
        std::vector<bullet::MeshContact>& contacts = t_contacts;
        contacts.clear();
        bullet::meshPairContacts(shape0, trans0, shape1, trans1, bullet::threadScratch(), contacts);
        addContacts(body0Wrap, body1Wrap, contacts);
    }
    finishPair();
}

}  // namespace cullide::bullet
