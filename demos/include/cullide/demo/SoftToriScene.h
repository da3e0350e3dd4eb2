// Two soft tori falling on each other onto a box floor in a btSoftRigidDynamicsWorld: soft-soft contacts through
// faces (VF_SS) and soft-rigid ones (SDF_RS). Shared by the adapter's soft-body tests and cullide-bench-softbody.
#pragma once

#include <memory>
#include <vector>

class btBoxShape;
class btRigidBody;
class btSoftBody;
class btSoftRigidDynamicsWorld;

namespace cullide::demo {

/// Sets `world`'s gravity to (0, -10, 0) and its soft-body info as Bullet's soft bodies need it before they are made:
/// the world's broadphase and dispatcher, the same gravity, the sparse SDF initialized.
void prepareSoftWorld(btSoftRigidDynamicsWorld& world);

class SoftToriScene {
public:
    /// Adds a static box floor (top at y = 0) and two tori of `segments` x `sides` quads (major radius 1, minor
    /// 0.35, margin 0.05, total mass 1 each) to `world`, whose world info (broadphase, dispatcher, sparse SDF) must
    /// be set up. The lower torus lies on the floor, the upper one 1.0 above it, tilted.
    explicit SoftToriScene(btSoftRigidDynamicsWorld& world, int segments = 24, int sides = 10);
    /// Removes the bodies from the world.
    ~SoftToriScene();
    SoftToriScene(const SoftToriScene&) = delete;
    SoftToriScene& operator=(const SoftToriScene&) = delete;

    /// Torus 0 (lower) or 1 (upper).
    btSoftBody& torus(int k) const { return *m_tori[static_cast<std::size_t>(k)]; }

private:
    btSoftRigidDynamicsWorld& m_world;
    std::unique_ptr<btBoxShape> m_groundShape;
    std::unique_ptr<btRigidBody> m_ground;
    std::vector<std::unique_ptr<btSoftBody>> m_tori;
};

}  // namespace cullide::demo
