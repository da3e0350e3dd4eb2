// Which results the adapter's shortcuts may write to.
#pragma once

#include <BulletCollision/CollisionDispatch/btManifoldResult.h>

#include <typeinfo>

namespace cullide::bullet {

/// Whether the result is the world's own (btManifoldResult exactly), which drops every point beyond the manifold's
/// breaking threshold: what the adapter's paths rely on when they skip triangles out of that reach or read the
/// culler's records. A result of another class may accept such points (btCollisionWorld::contactTest's
/// btBridgedManifoldResult checks no threshold; an application's own): Bullet's algorithm runs as it is then.
inline bool thresholdChecked(const btManifoldResult& result) { return typeid(result) == typeid(btManifoldResult); }

}  // namespace cullide::bullet
