// A GImpact mesh against a convex shape (or a concave shape's triangle): Bullet's per-triangle loop
// (btGImpactCollisionAlgorithm::gimpact_vs_shape for a mesh part) — the part's box-set query with the convex shape's
// box in the part's frame, then each candidate triangle, last to first, collided with the convex shape by the
// dispatcher's algorithm for the two, with Bullet's shape identifiers — minus the candidates that cannot make a point
// (convexCanTouch).
//
// The loop runs into the pair's own result and manifold on the dispatching thread, or ahead, in pieces, on the
// narrow-phase threads (convexChunkContacts), into a recording result: where the triangles' algorithms make their
// points whatever the manifold holds, the pair's algorithm then adds the recorded points to its manifold in their
// order, and the manifold is Bullet's bit for bit (Bullet's GImpact algorithm makes a new one every step).
#pragma once

#include "narrowphase/GImpactMeshContacts.h"

#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/CollisionDispatch/btCollisionObjectWrapper.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/Gimpact/btTriangleShapeEx.h>

#include <cstddef>
#include <vector>

class btCollisionDispatcher;

namespace cullide::bullet {

/// Where a GImpact triangle can still make a contact point with a convex shape: the convex shape's local box
/// (btCollisionShape::getAabb, margin included), the map from mesh-local to convex-local coordinates, the contact
/// breaking threshold and the float slack of the mapped coordinates.
struct ConvexReach {
    btTransform meshToConvex;
    btVector3 min, max;
    btScalar threshold = 0;
    btScalar slack = 0;
};

/// The reach of `meshWrap`'s triangles towards `convexWrap`'s shape.
ConvexReach convexReach(const btCollisionObjectWrapper& meshWrap, const btCollisionObjectWrapper& convexWrap);

/// False when the triangle's box, mapped into the convex shape's frame, stays farther from the convex shape's box
/// along an axis than the reach: the convex algorithm cannot make a point from it.
bool convexCanTouch(const btTriangleShapeEx& triangle, const ConvexReach& reach);

/// True when the whole mesh part lies within reach of the convex shape (then every candidate is kept).
bool partWithinReach(const btGImpactMeshShapePart& part, const ConvexReach& reach);

/// The two sides of a GImpact-convex loop: the mesh's wrapper, the convex shape's wrapper, and whether the convex
/// shape is the pair's first body.
struct ConvexSides {
    const btCollisionObjectWrapper* mesh;
    const btCollisionObjectWrapper* convex;
    bool convexFirst;
};

/// What the loop collides into: the dispatcher that makes each triangle's algorithm, the manifold it gets (made),
/// the result that receives the points, the dispatch's settings.
struct ConvexTarget {
    btDispatcher* dispatcher;
    btPersistentManifold* manifold;
    btManifoldResult* result;
    const btDispatcherInfo* info;
};

/// Shape identifiers as Bullet's loop sets them on the result: (part, triangle) of the first body, of the second.
/// The mesh side's triangle is each candidate's; the other side's stay as given (-1, or a concave shape's triangle).
struct ShapeIds {
    int part0 = -1, face0 = -1, part1 = -1, face1 = -1;
};

/// Bullet's box-set query of a mesh part (which must have a box set) with the convex shape's box in the part's frame:
/// the candidates appended to `out`, in the query's order.
void convexCandidates(const btTransform& meshTransform, const btGImpactMeshShapePart& part,
                      const btCollisionShape& convex, const btTransform& convexTransform,
                      btAlignedObjectArray<int>& out);

/// Bullet's loop over candidates[0, count) of one part: last to first, each as a triangle shape (the part's margin)
/// against the convex shape through the dispatcher's algorithm for the two in the pair's order, with `ids` (the mesh
/// side's triangle set to the candidate's) — minus the candidates out of reach. The part is locked.
void collideCandidates(const ConvexSides& sides, const btGImpactMeshShapePart& part, const int* candidates, int count,
                       ShapeIds ids, const ConvexTarget& target, ConvexCounts& counts);

/// Whether the loop's points can be computed ahead, in pieces and on any thread (convexChunkContacts): the
/// dispatcher's algorithm for the convex shape and a triangle (in the order they are collided) makes its points
/// whatever its manifold holds — Bullet's sphere-triangle one, or its convex one without perturbation iterations
/// (which would read how many points the manifold holds). bullet::convexTriangleThreadable checks the rest.
bool pointsIndependentOfManifold(const btCollisionAlgorithmCreateFunc* triangleFunc);

/// collideCandidates on a narrow-phase thread for part `partIndex` of the mesh (locked): the points recorded, in
/// the order the pair's result would receive them, with their shape identifiers, into `out`. The triangles'
/// algorithms get a manifold of their own with the contact breaking threshold `breakingThreshold` (what they read of
/// it; the pair's algorithm checks that its manifold has the same) and add nothing to it.
void convexChunkContacts(const ConvexSides& sides, int partIndex, const int* candidates, int count,
                         btScalar breakingThreshold, btCollisionDispatcher& dispatcher, const btDispatcherInfo& info,
                         std::vector<MeshContact>& out, ConvexCounts& counts);

/// Puts `wrap` in the result in place of the wrapper of its object for the scope, as Bullet's loops do around a
/// child shape (the contact's shape identifiers and callbacks see the child).
class WrapperInResult {
public:
    WrapperInResult(btManifoldResult& result, const btCollisionObjectWrapper& wrap);
    ~WrapperInResult();
    WrapperInResult(const WrapperInResult&) = delete;
    WrapperInResult& operator=(const WrapperInResult&) = delete;

private:
    btManifoldResult& m_result;
    bool m_first;
    const btCollisionObjectWrapper* m_previous;
};

}  // namespace cullide::bullet
