// A mesh whose spatial order is known: separate triangles along x, listed in a scrambled order (the triangle-order
// tests).
#pragma once

#include "cullide/Types.h"

#include <cstdint>

namespace cullide::test {

/// `n` separate triangles along x, listed in a scrambled order.
TriangleMesh triangleRow(std::uint32_t n);

}  // namespace cullide::test
