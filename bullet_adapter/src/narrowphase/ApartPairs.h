// Object pairs whose broadphase boxes are farther apart than any point their manifold could accept.
//
// btDbvtBroadphase keeps a pair while its fattened leaves overlap (a 0.05 margin, and until its lazy clean-up sees
// them apart), so Bullet's default pipeline runs the narrow phase (a GJK run for two hulls) on many pairs whose
// objects' own boxes do not meet; btAxisSweep3 holds only pairs whose boxes overlap. Such a pair can make no
// contact point: every algorithm adds its points through btManifoldResult::addContactPoint, which drops a point
// deeper than the manifold's contact breaking threshold t, and the boxes contain the shapes (with their margins),
// so the shapes are at least as far apart as the boxes. The dispatcher therefore skips the algorithm of a pair whose
// boxes are more than t apart and does to its manifolds what the algorithm's run would have done with no point found:
// btSphereSphereCollisionAlgorithm clears its manifold, the others refresh theirs (each point moved with the objects,
// dropped beyond t along its normal or drifted sideways by more than t). Most such points are dropped; a point whose
// objects went through each other along its normal (a negative distance: a fast body through a thin plate, a
// trigger through a trigger) stays, as in Bullet. So the narrow phase costs about what btAxisSweep3's does, while the
// pair cache, and so the simulation islands and every manifold point, stay btDbvtBroadphase's.
//
// Left to Bullet's own near callback (the algorithm runs as in Bullet): pairs the dispatch would not collide
// (needsCollision: sleeping contacts keep their points), a pair never processed yet (its algorithm and manifold are
// made as in Bullet), soft bodies and other non-rigid objects, GImpact shapes (Bullet's clip method can report points
// from triangle boxes that overlap only in its own box test; CULLIDE's records decide those pairs), heightfields
// (their box is the height range the application declares, which its data may exceed), cylinders whose radial half
// extents differ (Bullet's support mapping takes one as the radius on both radial axes, its box each on its own
// axis, so they reach beyond their box), algorithms whose run there
// could make or free a manifold (freesNoManifoldWhenApart: a compound algorithm that still holds child algorithms
// frees them, and with them their manifolds, which reorders the dispatcher's manifolds as the solver reads them;
// algorithms other than Bullet's convex ones), and every pair when the application installed its own near callback.
// An inactive object's box is taken from its shape at its present transform, not from its proxy: with
// btCollisionWorld::setForceUpdateAllAabbs(false) the world refreshes active objects' proxies only, and an application
// may move a static or sleeping object without updateSingleAabb. A shape that otherwise lies outside its own box (a
// compound with a heightfield child whose data exceeds its range, vertices changed without a refit) gets no points
// where it does, as with btAxisSweep3.
#pragma once

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <BulletCollision/BroadphaseCollision/btCollisionAlgorithm.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <LinearMath/btVector3.h>

namespace cullide::bullet {

/// The squared Euclidean distance between two axis-aligned boxes (0 when they touch or overlap).
btScalar boxDistanceSquared(const btVector3& min0, const btVector3& max0, const btVector3& min1,
                            const btVector3& max1);

/// The contact breaking threshold the dispatcher gives the pair's manifolds (btCollisionDispatcher::getNewManifold:
/// relative to the smaller shape when CD_USE_RELATIVE_CONTACT_BREAKING_THRESHOLD is set, else
/// gContactBreakingThreshold).
btScalar manifoldBreakingThreshold(const btCollisionDispatcher& dispatcher, const btCollisionObject& object0,
                                   const btCollisionObject& object1);

/// If the pair's algorithm can be skipped — both objects rigid bodies or plain collision objects, neither with a
/// GImpact shape, an algorithm already made that would make or free no manifold there, and their boxes (an inactive
/// object's from its shape at its transform) more than the breaking threshold of the pair (and of every manifold its
/// algorithm holds) apart — gives its manifolds the refresh (or, for two spheres, the clearing) that the algorithm's
/// run would give them (Bullet's contact callbacks run as there) and returns true. Otherwise changes nothing.
/// `scratch` is reused between calls. Pairs the dispatch would not collide (`needsCollision`) are left alone. The
/// caller checks the rest: discrete dispatch, Bullet's own near callback.
bool skipIfApart(btBroadphasePair& pair, btCollisionDispatcher& dispatcher, btManifoldArray& scratch);

}  // namespace cullide::bullet
