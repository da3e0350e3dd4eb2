// Small helpers over Bullet's proxies and transforms shared by the broadphase's parts.
#pragma once

#include "cullide/Types.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>

#include <cstdint>
#include <utility>

namespace cullide::bullet {

inline btCollisionObject* objectOf(const btBroadphaseProxy* p) {
    return static_cast<btCollisionObject*>(p->m_clientObject);
}

inline const btCollisionShape* shapeOf(const btBroadphaseProxy* p) {
    const btCollisionObject* o = objectOf(p);
    return o != nullptr ? o->getCollisionShape() : nullptr;
}

/// The key of the unordered pair (a, b): their unique ids, lower first.
inline std::uint64_t pairKey(const btBroadphaseProxy* a, const btBroadphaseProxy* b) {
    auto x = static_cast<std::uint32_t>(a->m_uniqueId);
    auto y = static_cast<std::uint32_t>(b->m_uniqueId);
    if (x > y) std::swap(x, y);
    return (static_cast<std::uint64_t>(x) << 32) | y;
}

inline Vec3 toVec(const btVector3& v) { return {double(v.x()), double(v.y()), double(v.z())}; }

/// A btTransform as the culler's Transform. World vertices are transformPoint(toTransform(t), local vertex)
/// everywhere (the culler for moving objects, the world meshes of static ones and the broadphase's own triangle
/// test), so all sides see bit-identical triangles.
inline Transform toTransform(const btTransform& t) {
    Transform out;
    const btMatrix3x3& basis = t.getBasis();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) out.linear(r, c) = double(basis[r][c]);
        out.translation[r] = double(t.getOrigin()[r]);
    }
    return out;
}

}  // namespace cullide::bullet
