// What the exact triangle tests share: triangles as three points, one-ulp steps, a printable form, the six vertex
// orders of a triangle, and a reference right triangle.
#pragma once

#include "cullide/TriangleTest.h"

#include <array>
#include <string>

namespace cullide::test {

using Tri = std::array<Vec3, 3>;

/// The next double above / below x.
double up(double x);
double down(double x);

/// The triangle's vertices in hexadecimal floating point (exact, for failure messages).
std::string str(const Tri& t);

/// The six orders of a triangle's three vertices.
inline constexpr int kPerms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

inline Vec3 V(double x, double y, double z) { return {x, y, z}; }

/// Reference right triangle in z = 0, hypotenuse x + y = 4.
inline const Tri kA = {V(0, 0, 0), V(4, 0, 0), V(0, 4, 0)};

/// triangleDistance of two triangles.
double dist(const Tri& a, const Tri& b);

}  // namespace cullide::test
