// The culling frame's objects (broadphase/CullFrame.h): a moving mesh goes in its own frame with its transform, keyed
// (Object::staticKey) so that the culler keeps its checks there, with a version that changes exactly when its
// geometry does; a resting static mesh goes world-space, keyed.
#include "BulletTestWorld.h"
#include "ProxyBody.h"
#include "broadphase/CullFrame.h"

#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <gtest/gtest.h>

#include <cstdint>

namespace cullide::test {
namespace {

using bullet::CullFrame;

/// The frame of one step with the single pair (a, b), and a's object in it.
Object enterPair(CullFrame& frame, ProxyBody& a, ProxyBody& b, std::uint64_t step) {
    CullideFrameStats stats;
    frame.beginStep();
    frame.build({{&a.proxy, &b.proxy}}, step, stats);
    for (std::uint32_t i = 0; i < frame.objects().size(); ++i)
        if (frame.proxyOf(i) == &a.proxy) return frame.objects()[i];
    ADD_FAILURE() << "the body is not in the frame";
    return Object{};
}

TEST(CullFrame, AMovingMeshIsKeyedAndItsVersionFollowsItsGeometry) {
    ShapeStore shapes;
    btCollisionShape* torus = shapes.gimpactTorus(1, btScalar(0.3), 16, 8, btScalar(0.04));
    ProxyBody moving(torus, btTransform::getIdentity(), 1);
    ProxyBody other(shapes.sphere(btScalar(0.5)), btTransform(btQuaternion::getIdentity(), btVector3(1, 0, 0)), 2);
    CullFrame frame;

    const Object first = enterPair(frame, moving, other, 1);
    ASSERT_NE(first.mesh, nullptr);
    ASSERT_NE(first.transform, nullptr);  // in its own frame
    EXPECT_NE(first.staticKey, 0u);

    const btQuaternion turn(btVector3(0, 1, 0), btScalar(0.3));
    moving.object.setWorldTransform(btTransform(turn, btVector3(0, btScalar(0.1), 0)));
    const Object second = enterPair(frame, moving, other, 2);
    EXPECT_EQ(second.staticKey, first.staticKey);
    EXPECT_EQ(second.version, first.version) << "moving changes no geometry";

    const Vec3 before = second.mesh->vertices[0];  // the old geometry goes with the step that replaces it
    torus->setLocalScaling(btVector3(btScalar(1.2), 1, 1));  // another geometry in the same shape
    static_cast<btGImpactMeshShape*>(torus)->updateBound();
    const Object third = enterPair(frame, moving, other, 3);
    EXPECT_EQ(third.staticKey, first.staticKey);
    EXPECT_NE(third.version, second.version) << "the culler would keep the old geometry's checks and boxes";
    EXPECT_NE(third.mesh->vertices[0], before);

    // The world-space copy the narrow phase asks for (updateWorld, each time the body moves) is another mesh: the
    // local mesh's key and version stay as they are.
    bullet::updateWorld(frame.culled(&moving.proxy), moving.object.getWorldTransform());
    const Object fourth = enterPair(frame, moving, other, 4);
    EXPECT_EQ(fourth.staticKey, first.staticKey);
    EXPECT_EQ(fourth.version, third.version) << "the culler would start the mesh over every step";
}

}  // namespace
}  // namespace cullide::test
