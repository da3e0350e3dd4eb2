// Geometry checks of generated meshes and scenes, independent of the code under test: orientation, volume,
// intersection, sameness, deformation (the scene tests).
#pragma once

#include "cullide/Types.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace cullide::test {

inline constexpr double kPi = 3.1415926535897932384626433832795;

using Edge = std::pair<std::uint32_t, std::uint32_t>;

/// How many times each directed edge occurs in the mesh's triangles.
std::map<Edge, int> directedEdges(const TriangleMesh& m);

/// Closed, consistently oriented 2-manifold: every directed edge once, its reverse once.
::testing::AssertionResult isClosedOriented(const TriangleMesh& m);

double signedVolume(const TriangleMesh& m);

/// Volume of an oriented mesh whose boundary loops are closed by fans from each loop's centroid (open cylinders).
double cappedVolume(const TriangleMesh& m);

/// True iff some triangle of `a` intersects some triangle of `b` (uniform grid over the boxes' overlap).
bool anyIntersection(const TriangleMesh& a, const TriangleMesh& b);

bool sameMeshes(const std::vector<TriangleMesh>& x, const std::vector<TriangleMesh>& y);

/// Relative change of a few vertex-to-vertex distances: zero for rigid motions.
double shapeChange(const TriangleMesh& p, const TriangleMesh& q);

}  // namespace cullide::test
