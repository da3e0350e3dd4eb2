// Random rigid poses for the GImpact narrow-phase tests: a random rotation and a translation within `spread`.
#pragma once

#include <LinearMath/btScalar.h>
#include <LinearMath/btTransform.h>

#include <random>

namespace cullide::test {

/// A random rotation and a translation uniform in [-spread, spread] along each axis.
btTransform randomPose(std::mt19937& rng, btScalar spread);

}  // namespace cullide::test
