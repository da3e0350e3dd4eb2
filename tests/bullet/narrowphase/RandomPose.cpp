#include "RandomPose.h"

namespace cullide::test {

btTransform randomPose(std::mt19937& rng, btScalar spread) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    btQuaternion q(u(rng), u(rng), u(rng), u(rng) + 1.5f);
    q.normalize();
    return btTransform(q, btVector3(spread * u(rng), spread * u(rng), spread * u(rng)));
}

}  // namespace cullide::test
