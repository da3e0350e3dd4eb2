// What the adapter's GImpact algorithms share: each is a btGImpactCollisionAlgorithm (so that any pair its shortcut
// does not cover runs Bullet's own processCollision, unchanged), made with the dispatcher's NarrowPhaseContext.
// One subclass per pair kind (AlgorithmTable.h chooses): GImpactMeshMeshAlgorithm, GImpactConcaveAlgorithm,
// GImpactConvexAlgorithm, GImpactPlaneAlgorithm.
#pragma once

#include "narrowphase/GImpactConvexContacts.h"
#include "narrowphase/GImpactMeshContacts.h"
#include "narrowphase/NarrowPhaseContext.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <vector>

namespace cullide::bullet {

class GImpactAlgorithmBase : public btGImpactCollisionAlgorithm {
public:
    GImpactAlgorithmBase(const btCollisionAlgorithmConstructionInfo& ci, const btCollisionObjectWrapper* body0Wrap,
                         const btCollisionObjectWrapper* body1Wrap, NarrowPhaseContext& context)
        : btGImpactCollisionAlgorithm(ci, body0Wrap, body1Wrap), m_context(context) {}

    /// A btGImpactMeshShape (not a GImpact compound, not a lone mesh part).
    static bool isGImpactMesh(const btCollisionObjectWrapper& w);
    /// A GImpact triangle mesh (`mesh`) against a convex shape that is not a compound (`convex`).
    static bool trimeshAgainstConvex(const btCollisionObjectWrapper* mesh, const btCollisionObjectWrapper* convex);
    /// A GImpact triangle mesh (`mesh`) against a static plane (`plane`), where Bullet's algorithm collides the two by
    /// the mesh's vertices (GIMPACT_VS_PLANE_COLLISION).
    static bool trimeshAgainstPlane(const btCollisionObjectWrapper* mesh, const btCollisionObjectWrapper* plane);

protected:
    /// Whether the adapter's paths give Bullet's points here: the world's own result (thresholdChecked), and, with
    /// SAT convex collision on (btDispatcherInfo::m_enableSatConvex), where Bullet's convex-triangle algorithm clips
    /// polyhedral faces, which the skip's reach test does not model, only GImpact against another GImpact mesh or a
    /// plane (whose points are computed as Bullet computes them).
    static bool shortcutsSound(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                               const btDispatcherInfo& dispatchInfo, const btManifoldResult& resultOut);

    /// Bullet's own algorithm, unchanged.
    void processAsBulletDoes(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                             const btDispatcherInfo& dispatchInfo, btManifoldResult* resultOut) {
        btGImpactCollisionAlgorithm::processCollision(body0Wrap, body1Wrap, dispatchInfo, resultOut);
    }
    /// What btGImpactCollisionAlgorithm::processCollision does first: the manifold of the last call dropped (GImpact
    /// rebuilds it every step), the result and dispatch info kept for addContactPoint.
    void beginPair(btManifoldResult* resultOut, const btDispatcherInfo& dispatchInfo) {
        clearCache();
        m_resultOut = resultOut;
        m_dispatchInfo = &dispatchInfo;
    }
    /// What it does last: the manifold's points refreshed, if the pair has one.
    void finishPair() {
        if (getLastManifold() != nullptr) m_resultOut->refreshContactPoints();
    }

    /// The points in order through Bullet's addContactPoint, each with its shape identifiers (as
    /// collide_sat_triangles adds them).
    void addContacts(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                     const std::vector<bullet::MeshContact>& points);
    void addContact(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                    const bullet::MeshContact& c);

    /// Bullet's gimpact_vs_shape for one GImpact mesh part against a convex shape: the part's box query with the
    /// convex shape's box in the part's frame, then the candidates through bullet::collideCandidates (Bullet's loop
    /// minus the candidates out of reach) into the pair's result.
    void partAgainstConvex(const btCollisionObjectWrapper* meshWrap, const btGImpactMeshShapePart& meshPart,
                           const btCollisionObjectWrapper* convexWrap, bool swapped);
    void addCounts(const bullet::ConvexCounts& counts);

    NarrowPhaseContext& m_context;
};

}  // namespace cullide::bullet
