// The adapter's collision algorithms, one per pair kind, and which pairs they take over from the algorithms the
// application's collision configuration registered (btCollisionDispatcher's double-dispatch table).
//
//   kind               shapes (either order)                                      algorithm
//   GImpactGImpact     GImpact - GImpact                                          GImpactMeshMeshAlgorithm
//   GImpactConcave     GImpact - triangle mesh, heightfield, ... (not a plane)    GImpactConcaveAlgorithm
//   GImpactConvex      GImpact mesh - convex shape (not a compound)               GImpactConvexAlgorithm
//   GImpactPlane       GImpact mesh - static plane (GIMPACT_VS_PLANE_COLLISION)   GImpactPlaneAlgorithm
//   ConvexMesh         culled hull or compound child - triangle mesh              ConvexMeshAlgorithm
//
// A GImpact kind replaces only Bullet's own btGImpactCollisionAlgorithm (registered by
// btGImpactCollisionAlgorithm::registerAlgorithm, as Bullet's own dispatcher requires), and ConvexMesh only Bullet's
// btConvexConcaveCollisionAlgorithm while convex-mesh culling is on: an application's own registration wins.
#pragma once

#include "cullide_bullet/CullideBroadphase.h"
#include "narrowphase/ConvexMeshAlgorithm.h"
#include "narrowphase/GImpactAlgorithmBase.h"
#include "narrowphase/GImpactConcaveAlgorithm.h"
#include "narrowphase/GImpactConvexAlgorithm.h"
#include "narrowphase/GImpactMeshMeshAlgorithm.h"
#include "narrowphase/GImpactPlaneAlgorithm.h"

#include <array>
#include <typeinfo>

namespace cullide::bullet {

/// Whether `f` is exactly a creation function of class T (not a subclass: an application's own).
template <typename T>
bool registeredIs(const btCollisionAlgorithmCreateFunc* f) {
    return f != nullptr && typeid(*f) == typeid(T);
}

/// Makes algorithms of class `Algorithm` with a dispatcher's context, in memory from the dispatcher (its pool, or the
/// heap: CullideCollisionDispatcher::allocateCollisionAlgorithm), as Bullet's own creation functions do.
template <class Algorithm>
struct CreateWithContext final : btCollisionAlgorithmCreateFunc {
    explicit CreateWithContext(NarrowPhaseContext& context) : m_context(context) {}
    btCollisionAlgorithm* CreateCollisionAlgorithm(btCollisionAlgorithmConstructionInfo& ci,
                                                   const btCollisionObjectWrapper* body0Wrap,
                                                   const btCollisionObjectWrapper* body1Wrap) override {
        void* mem = ci.m_dispatcher1->allocateCollisionAlgorithm(sizeof(Algorithm));
        return new (mem) Algorithm(ci, body0Wrap, body1Wrap, m_context);
    }
    NarrowPhaseContext& m_context;
};

class AlgorithmTable {
public:
    enum class Kind : int { None = -1, GImpactGImpact, GImpactConcave, GImpactConvex, GImpactPlane, ConvexMesh,
                            MeshConvex };

    explicit AlgorithmTable(NarrowPhaseContext& context);
    AlgorithmTable(const AlgorithmTable&) = delete;
    AlgorithmTable& operator=(const AlgorithmTable&) = delete;

    /// The pair's kind if one of the adapter's algorithms takes it over from `registered` (the application's table
    /// entry for the two shape types), else Kind::None. `broadphase` says whether convex-mesh pairs may be culled
    /// (asked only for such pairs: most lookups come from per-triangle loops).
    static Kind kindOf(const btCollisionObjectWrapper* body0Wrap, const btCollisionObjectWrapper* body1Wrap,
                       const btCollisionAlgorithmCreateFunc* registered, const CullideBroadphase& broadphase);

    /// The creation function of the adapter's algorithm for the pair, or nullptr to keep `registered`.
    btCollisionAlgorithmCreateFunc* replacementFor(const btCollisionObjectWrapper* body0Wrap,
                                                   const btCollisionObjectWrapper* body1Wrap,
                                                   const btCollisionAlgorithmCreateFunc* registered,
                                                   const CullideBroadphase& broadphase);

private:
    CreateWithContext<GImpactMeshMeshAlgorithm> m_gimpactGImpact;
    CreateWithContext<GImpactConcaveAlgorithm> m_gimpactConcave;
    CreateWithContext<GImpactConvexAlgorithm> m_gimpactConvex;
    CreateWithContext<GImpactPlaneAlgorithm> m_gimpactPlane;
    CreateWithContext<ConvexMeshAlgorithm<false>> m_convexMesh;
    CreateWithContext<ConvexMeshAlgorithm<true>> m_meshConvex;
    /// Indexed by Kind.
    std::array<btCollisionAlgorithmCreateFunc*, 6> m_entries;
};

}  // namespace cullide::bullet
