// Helpers to compare culler results against the brute-force reference.
#pragma once

#include "cullide/Culler.h"

#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace cullide::test {

using FlatPair = std::array<std::uint32_t, 4>;  // object a, triangle of a, object b, triangle of b

std::set<FlatPair> trianglePairs(const Result& result);

struct Comparison {
    std::size_t expected = 0;
    std::size_t missed = 0;      ///< in the reference, not in the result (or not in its pcsTriangles)
    std::size_t spurious = 0;    ///< in the result, not in the reference
    std::string firstMissed;
    bool objectPairsEqual = false;  ///< same object pairs (a, b, hasTriangles) and the same PCS
};
Comparison compare(const Result& reference, const Result& result);

/// One frame of `objects` on `tested` (into `got`) and on `reference`, compared.
Comparison runAndCompare(Culler& tested, Culler& reference, const std::vector<Object>& objects, Result& got);

/// Seeded soup scene: `objects` clusters of random triangles (some degenerate) in the unit cube.
std::vector<TriangleMesh> randomSoups(std::uint64_t seed, int objects, int trianglesPerObject, double clusterSize);

std::vector<Object> asObjects(const std::vector<TriangleMesh>& meshes);

}  // namespace cullide::test
