// A GImpact mesh part against a static plane: Bullet's contacts (btGImpactCollisionAlgorithm::
// gimpacttrimeshpart_vs_plane_collision) at a fraction of its cost.
//
// Bullet's loop: when the part's box (widened by the plane's margin) reaches the plane, every vertex of the part, last
// to first, is mapped to world space, and each that lies nearer the plane than the two margins makes a point at the
// vertex, with the plane's normal. A mesh resting on the ground has all of its vertices mapped every step, though few
// are near the plane.
//
// Here a filter reads each vertex straight from the mesh's arrays and bounds Bullet's distance from below: the plane
// taken into the part's frame (one dot product a vertex), less a bound on the rounding error of Bullet's arithmetic and
// of its own for that vertex. Only the vertices the filter cannot rule out go through Bullet's test, with
// Bullet's operations in Bullet's order: the same points, bit for bit. It reads the vertices as they are now: a
// deformed mesh needs no refit for it (Bullet's box test before the loop still reads the part's box as last updated).
#pragma once

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <LinearMath/btTransform.h>
#include <LinearMath/btVector3.h>

#include <cstddef>
#include <functional>

namespace cullide::bullet {

/// The plane in a part's frame: a lower bound of Bullet's distance (less the margins) of a vertex from its stored
/// coordinates (before the mesh's scaling), and the error bound that makes it safe.
class PlaneFilter {
public:
    PlaneFilter(const btTransform& partTransform, const btVector3& scaling, const btVector4& equation, btScalar margin);

    /// False only where Bullet's distance of the vertex is certainly not below zero (no point). Not-a-number
    /// coordinates pass: Bullet's test decides them.
    bool mayTouch(btScalar x, btScalar y, btScalar z) const {
        const btScalar distance = m_normal[0] * x + m_normal[1] * y + m_normal[2] * z + m_offset;
        const btScalar error = m_error[0] * btFabs(x) + m_error[1] * btFabs(y) + m_error[2] * btFabs(z) + m_errorOffset;
        return !(distance > error);
    }

    const btScalar* normal() const { return m_normal; }
    btScalar offset() const { return m_offset; }
    const btScalar* error() const { return m_error; }
    btScalar errorOffset() const { return m_errorOffset; }

private:
    btScalar m_normal[3];  // the plane's normal in the part's frame, times the scaling
    btScalar m_offset;     // the distance of the part's origin, less the plane's constant and the margins
    btScalar m_error[3];   // per coordinate: the float error of Bullet's distance and of this one per unit |coordinate|
    btScalar m_errorOffset;
};

/// Receives a point of Bullet's plane loop: the vertex in world space and its distance (less the margins).
using PlanePointSink = std::function<void(const btVector3& vertex, btScalar distance)>;

/// Vertices of the parts whose box reached the plane (Bullet maps each) and of those, the ones the filter let
/// through to Bullet's test.
struct PlaneCounts {
    std::size_t vertices = 0;
    std::size_t tested = 0;
};

/// The plane's equation in world space, (normal, constant), as Bullet's GImpact algorithm computes it.
btVector4 planeEquation(const btStaticPlaneShape& plane, const btTransform& planeTransform);

/// Bullet's points of `part` at `partTransform` against the plane `equation` (planeEquation) with margin
/// `planeMargin`, handed to `add` in Bullet's order while the part is locked, as Bullet adds them (nothing when the
/// part's box does not reach the plane).
void planePartContacts(const btGImpactMeshShapePart& part, const btTransform& partTransform, const btVector4& equation,
                       btScalar planeMargin, const PlanePointSink& add, PlaneCounts& counts);

}  // namespace cullide::bullet
