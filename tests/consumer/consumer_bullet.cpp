// The README's two-line swap in a downstream project: a box dropped on a ground box in a btDiscreteDynamicsWorld,
// with CullideBroadphase and CullideCollisionDispatcher in place of btDbvtBroadphase and btCollisionDispatcher.
// Nothing else is CULLIDE-specific. Exit 0 when the box comes to rest on the ground.
#include <cullide_bullet/CullideBroadphase.h>
#include <cullide_bullet/CullideCollisionDispatcher.h>

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <cstdio>

int main() {
    btDefaultCollisionConfiguration config;
    cullide::CullideBroadphase broadphase;                          // was: btDbvtBroadphase
    cullide::CullideCollisionDispatcher dispatcher(&config, &broadphase);  // was: btCollisionDispatcher(&config)
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    world.setGravity(btVector3(0, -10, 0));

    btBoxShape groundShape(btVector3(10, 1, 10));
    btRigidBody ground(0, nullptr, &groundShape);
    world.addRigidBody(&ground);

    btBoxShape boxShape(btVector3(0.5, 0.5, 0.5));
    btVector3 inertia;
    boxShape.calculateLocalInertia(1, inertia);
    btDefaultMotionState motion(btTransform(btQuaternion::getIdentity(), btVector3(0, 3, 0)));
    btRigidBody box(btRigidBody::btRigidBodyConstructionInfo(1, &motion, &boxShape, inertia));
    world.addRigidBody(&box);

    int contacts = 0;
    for (int step = 0; step < 180; ++step) {
        world.stepSimulation(1.0f / 60, 1, 1.0f / 60);
        for (int i = 0; i < dispatcher.getNumManifolds(); ++i)
            contacts += dispatcher.getManifoldByIndexInternal(i)->getNumContacts();
    }
    const btScalar y = box.getWorldTransform().getOrigin().y();
    world.removeRigidBody(&box);
    world.removeRigidBody(&ground);
    std::printf("consumer_bullet: box at y = %.3f after 3 s, %d contact point-steps\n", double(y), contacts);
    return contacts > 0 && std::fabs(double(y) - 1.5) < 0.05 ? 0 : 1;
}
