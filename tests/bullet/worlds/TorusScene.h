// A loose, twisted column of GImpact tori dropped on a static plane (the GImpact scene of the world tests and the
// determinism test).
#pragma once

#include "BulletTestWorld.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>

#include <cmath>

namespace cullide::test {

struct TorusScene {
    ShapeStore shapes;
    btCollisionShape* plane = nullptr;
    btCollisionShape* torus = nullptr;
    int count = 8;

    TorusScene() {
        plane = shapes.plane(btVector3(0, 1, 0), 0);
        torus = shapes.gimpactTorus(1, btScalar(0.3), 24, 12, btScalar(0.04));
    }

    void populate(TestWorld& w) const {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(plane, 0, btTransform::getIdentity());
        for (int k = 0; k < count; ++k) {
            // A loose, twisted column: every torus lands on the one below (or the plane) a little off-centre.
            const btQuaternion q(btVector3(1, 0, btScalar(0.3) * btScalar(k % 3)).normalized(),
                                 btScalar(0.5) + btScalar(0.7) * btScalar(k));
            const btVector3 p(btScalar(0.35) * std::sin(btScalar(k)), btScalar(1.5) + btScalar(1.7) * btScalar(k),
                              btScalar(0.35) * std::cos(btScalar(1.3) * btScalar(k)));
            w.addBody(torus, 1, btTransform(q, p));
        }
    }
};

}  // namespace cullide::test
