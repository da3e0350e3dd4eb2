// A collision object with a broadphase proxy of its own, outside any world: what the broadphase's parts (CullFrame,
// PairRecords) take, without a Bullet world around them.
#pragma once

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <LinearMath/btTransform.h>

namespace cullide::test {

/// A moving collision object (no collision flags) with its proxy, whose unique id the test chooses (a pair record's
/// key, and which object is a record's first: the lower id).
struct ProxyBody {
    btCollisionObject object;
    btBroadphaseProxy proxy;

    ProxyBody(btCollisionShape* shape, const btTransform& t, int uniqueId) {
        object.setCollisionShape(shape);
        object.setWorldTransform(t);
        object.setCollisionFlags(0);
        btVector3 min, max;
        shape->getAabb(t, min, max);
        proxy = btBroadphaseProxy(min, max, &object, 1, -1);
        proxy.m_uniqueId = uniqueId;
        object.setBroadphaseHandle(&proxy);
    }
    ProxyBody(const ProxyBody&) = delete;
    ProxyBody& operator=(const ProxyBody&) = delete;
};

}  // namespace cullide::test
