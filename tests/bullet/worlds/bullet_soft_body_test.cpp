// btSoftRigidDynamicsWorld with CULLIDE's broadphase and dispatcher: a cloth falls onto a static sphere and a
// resting rigid box; two soft tori fall on each other. Soft bodies are box proxies for the culler (their contacts
// live in the soft body, not in manifolds), so they must end up exactly where they do with Bullet's default
// pipeline.
#include "SceneSupport.h"

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>

#include "cullide/demo/SoftToriScene.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace cullide::test {
namespace {

/// A btSoftRigidDynamicsWorld with either pipeline (gravity -10 y).
struct SoftWorld {
    btSoftBodyRigidBodyCollisionConfiguration config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    btSequentialImpulseConstraintSolver solver;
    std::unique_ptr<btSoftRigidDynamicsWorld> world;

    explicit SoftWorld(PipelineKind kind) {
        if (kind == PipelineKind::Default) {
            broadphase = std::make_unique<btDbvtBroadphase>();
            dispatcher = std::make_unique<btCollisionDispatcher>(&config);
        } else {
            auto bp = std::make_unique<CullideBroadphase>(Settings{}, nullptr, gpuFactory());
            dispatcher = std::make_unique<CullideCollisionDispatcher>(&config, bp.get());
            broadphase = std::move(bp);
        }
        world = std::make_unique<btSoftRigidDynamicsWorld>(dispatcher.get(), broadphase.get(), &solver, &config);
        demo::prepareSoftWorld(*world);
    }
};

std::vector<btVector3> runCloth(PipelineKind kind) {
    SoftWorld soft(kind);
    btSoftRigidDynamicsWorld& world = *soft.world;
    btSoftBodyWorldInfo& info = world.getWorldInfo();

    btBoxShape groundShape(btVector3(10, 1, 10));
    btBoxShape boxShape(btVector3(btScalar(0.6), btScalar(0.6), btScalar(0.6)));
    btRigidBody ground(0, nullptr, &groundShape);
    ground.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)));
    world.addRigidBody(&ground);
    btVector3 inertia;
    boxShape.calculateLocalInertia(1, inertia);
    btRigidBody box(1, nullptr, &boxShape, inertia);
    box.setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(0.5), btScalar(0.6), 0)));
    world.addRigidBody(&box);
    btSphereShape sphereShape(btScalar(0.6));
    btRigidBody sphere(0, nullptr, &sphereShape);
    sphere.setWorldTransform(
        btTransform(btQuaternion::getIdentity(), btVector3(-btScalar(1.1), btScalar(0.6), btScalar(0.5))));
    world.addRigidBody(&sphere);

    std::unique_ptr<btSoftBody> cloth(btSoftBodyHelpers::CreatePatch(
        info, btVector3(-2, 3, -2), btVector3(2, 3, -2), btVector3(-2, 3, 2), btVector3(2, 3, 2), 12, 12, 0, true));
    cloth->getCollisionShape()->setMargin(btScalar(0.05));
    cloth->setTotalMass(1);
    cloth->m_cfg.piterations = 4;
    world.addSoftBody(cloth.get());
    for (int s = 0; s < 180; ++s) world.stepSimulation(btScalar(1.0 / 60.0), 1, btScalar(1.0 / 60.0));
    std::vector<btVector3> nodes;
    for (int i = 0; i < cloth->m_nodes.size(); ++i) nodes.push_back(cloth->m_nodes[i].m_x);
    nodes.push_back(box.getWorldTransform().getOrigin());
    world.removeSoftBody(cloth.get());
    world.removeRigidBody(&sphere);
    world.removeRigidBody(&box);
    world.removeRigidBody(&ground);
    return nodes;
}

TEST(BulletSoftBody, ClothSettlesExactlyAsWithDefaultPipeline) {
    CULLIDE_BULLET_REQUIRE_GL();
    const std::vector<btVector3> a = runCloth(PipelineKind::Default);
    const std::vector<btVector3> b = runCloth(PipelineKind::Cullide);
    ASSERT_EQ(a.size(), b.size());
    double maxDeviation = 0.0;
    btScalar lowest = 1e9;
    for (std::size_t i = 0; i < a.size(); ++i) {
        maxDeviation = std::max(maxDeviation, double((a[i] - b[i]).length()));
        lowest = std::min(lowest, b[i].y());
    }
    std::printf("[soft body] %zu cloth nodes after 180 steps: max deviation from the default pipeline %.3e, lowest "
                "node y %.3f\n",
                a.size() - 1, maxDeviation, double(lowest));
    EXPECT_GT(lowest, btScalar(-0.1)) << "the cloth fell through the ground";
    btScalar overSphere = -1e9;  // the highest cloth node above the sphere's centre
    for (std::size_t i = 0; i + 1 < b.size(); ++i)
        if (btVector3(b[i].x() + btScalar(1.1), 0, b[i].z() - btScalar(0.5)).length() < btScalar(0.4))
            overSphere = std::max(overSphere, b[i].y());
    std::printf("[soft body] highest cloth node over the sphere y %.3f (sphere top 1.2)\n", double(overSphere));
    EXPECT_GT(overSphere, btScalar(1.1)) << "the cloth does not rest on the sphere";
    EXPECT_LT(maxDeviation, 1e-4);
}

/// Two soft tori (VF_SS: soft-soft collisions through faces, SDF_RS against rigid bodies) dropped on each other and
/// on a box floor. Returns the nodes of both tori after `steps` steps.
std::vector<btVector3> runSoftTori(PipelineKind kind, int steps) {
    SoftWorld soft(kind);
    btSoftRigidDynamicsWorld& world = *soft.world;
    const demo::SoftToriScene scene(world);
    for (int s = 0; s < steps; ++s) world.stepSimulation(btScalar(1.0 / 60.0), 1, btScalar(1.0 / 60.0));
    std::vector<btVector3> nodes;
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < scene.torus(k).m_nodes.size(); ++i) nodes.push_back(scene.torus(k).m_nodes[i].m_x);
    return nodes;
}

TEST(BulletSoftBody, SoftToriCollideFaceToFaceAsWithDefaultPipeline) {
    // Soft-soft collisions (VF_SS) run inside the soft bodies on their own face trees, started by the broadphase
    // pair: CULLIDE's pairs must start them exactly when Bullet's do. Soft bodies are box proxies for the culler;
    // restricting VF_SS to the culler's surviving faces is not done (Bullet's per-body face trees already prune).
    CULLIDE_BULLET_REQUIRE_GL();
    const int steps = 150;
    const std::vector<btVector3> a = runSoftTori(PipelineKind::Default, steps);
    const std::vector<btVector3> b = runSoftTori(PipelineKind::Cullide, steps);
    ASSERT_EQ(a.size(), b.size());
    double maxDeviation = 0.0;
    btScalar lowestUpper = 1e9;
    for (std::size_t i = 0; i < a.size(); ++i) maxDeviation = std::max(maxDeviation, double((a[i] - b[i]).length()));
    for (std::size_t i = a.size() / 2; i < a.size(); ++i) lowestUpper = std::min(lowestUpper, b[i].y());
    std::printf("[soft tori] %zu nodes after %d steps: max deviation from the default pipeline %.3e, lowest node of "
                "the upper torus y %.3f\n", a.size(), steps, maxDeviation, double(lowestUpper));
    EXPECT_GT(lowestUpper, btScalar(0.2)) << "the upper torus must rest on the lower one (VF_SS), not on the floor";
    EXPECT_LT(maxDeviation, 1e-4);
}

}  // namespace
}  // namespace cullide::test
