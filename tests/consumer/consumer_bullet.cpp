// The two-line swap in a downstream project. The CPU reference culler stands in for the GPU one, so this runs on
// machines without GL too; everything else is what an application writes.
#include <cullide_bullet/CullideBroadphase.h>
#include <cullide_bullet/CullideCollisionDispatcher.h>

#include <btBulletCollisionCommon.h>

#include <cstdio>

int main() {
    btDefaultCollisionConfiguration config;
    cullide::CullideBroadphase broadphase(cullide::Settings{}, nullptr, cullide::createReferenceCuller);
    cullide::CullideCollisionDispatcher dispatcher(&config, &broadphase);
    btCollisionWorld world(&dispatcher, &broadphase, &config);
    btBoxShape box(btVector3(1, 1, 1));
    btCollisionObject a, b;
    a.setCollisionShape(&box);
    b.setCollisionShape(&box);
    b.getWorldTransform().setOrigin(btVector3(1.5, 0, 0));
    b.setCollisionFlags(0);  // a plain btCollisionObject is static, and static-static pairs never collide
    world.addCollisionObject(&a);
    world.addCollisionObject(&b);
    world.performDiscreteCollisionDetection();
    int contacts = 0;
    for (int i = 0; i < dispatcher.getNumManifolds(); ++i) contacts += dispatcher.getManifoldByIndexInternal(i)->getNumContacts();
    world.removeCollisionObject(&b);
    world.removeCollisionObject(&a);
    std::printf("consumer_bullet: %d contact(s)\n", contacts);
    return contacts > 0 ? 0 : 1;
}
