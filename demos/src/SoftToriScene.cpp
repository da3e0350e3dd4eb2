#include "cullide/demo/SoftToriScene.h"

#include "cullide/scenes/Procedural.h"

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

namespace cullide::demo {

void prepareSoftWorld(btSoftRigidDynamicsWorld& world) {
    world.setGravity(btVector3(0, -10, 0));
    btSoftBodyWorldInfo& info = world.getWorldInfo();
    info.m_broadphase = world.getBroadphase();
    info.m_dispatcher = world.getDispatcher();
    info.m_gravity = world.getGravity();
    info.m_sparsesdf.Initialize();
}

SoftToriScene::SoftToriScene(btSoftRigidDynamicsWorld& world, int segments, int sides) : m_world(world) {
    m_groundShape = std::make_unique<btBoxShape>(btVector3(10, 1, 10));
    m_ground = std::make_unique<btRigidBody>(0, nullptr, m_groundShape.get());
    m_ground->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(0, -1, 0)));
    world.addRigidBody(m_ground.get());

    btSoftBodyWorldInfo& info = world.getWorldInfo();
    for (int k = 0; k < 2; ++k) {
        TriangleMesh mesh = scenes::makeTorus(1.0, 0.35, segments, sides);
        scenes::transformMesh(mesh, Eigen::Translation3d(0.3 * k, 0.5 + 1.0 * k, 0.1 * k) *
                                        Eigen::AngleAxisd(1.5707963 + 0.4 * k, Vec3(1, 0, 0.2 * k).normalized()));
        std::vector<btScalar> vertices;
        std::vector<int> indices;
        for (const Vec3& v : mesh.vertices)
            vertices.insert(vertices.end(), {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())});
        for (const auto& t : mesh.triangles) indices.insert(indices.end(), {int(t[0]), int(t[1]), int(t[2])});
        m_tori.emplace_back(btSoftBodyHelpers::CreateFromTriMesh(info, vertices.data(), indices.data(),
                                                                 int(mesh.triangles.size()), false));
        btSoftBody& sb = *m_tori.back();
        sb.m_cfg.collisions = btSoftBody::fCollision::SDF_RS | btSoftBody::fCollision::VF_SS;
        sb.m_cfg.piterations = 4;
        sb.m_cfg.kDF = btScalar(0.5);
        sb.m_materials[0]->m_kLST = btScalar(0.4);
        sb.generateBendingConstraints(2);
        sb.getCollisionShape()->setMargin(btScalar(0.05));
        sb.setTotalMass(1);
        world.addSoftBody(&sb);
    }
}

SoftToriScene::~SoftToriScene() {
    for (auto& sb : m_tori) m_world.removeSoftBody(sb.get());
    m_world.removeRigidBody(m_ground.get());
}

}  // namespace cullide::demo
