// The exact stage's test of one candidate pair.
#pragma once

#include "cullide/Types.h"

namespace cullide {

/// trianglesWithin (cullide/TriangleTest.h) for a pair whose boxes are already known to meet within `margin` (each
/// box inflated by margin / 2: the box tree's leaf pairs): the same answer, without the box early-out, which
/// cannot end such a pair. The result does not depend on the boxes meeting; only the time does.
bool candidateWithin(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0, const Vec3& b1,
                     const Vec3& b2, double margin);

}  // namespace cullide
