// The CPU path's trees of whole meshes (MeshTrees) without GL: the triangle-level PCS of such a mesh, listed from
// its pairs.
#include "MeshTrees.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <vector>

namespace cullide::test {
namespace {

/// Pairs (object 0, object 1) and (object 2, object 0) with random sorted triangle pairs: `perPair` each, triangles
/// of object 0 below `count`.
Result randomPairs(std::mt19937& rng, std::size_t perPair, std::uint32_t count) {
    Result result;
    for (const auto& [a, b] : {std::pair<std::uint32_t, std::uint32_t>{0, 1}, {2, 0}}) {
        ObjectPair pair;
        pair.a = a;
        pair.b = b;
        pair.hasTriangles = true;
        std::uniform_int_distribution<std::uint32_t> any(0, count - 1);
        std::set<TrianglePair> unique;
        while (unique.size() < perPair) unique.insert({any(rng), any(rng)});
        pair.triangles.assign(unique.begin(), unique.end());
        result.pairs.push_back(pair);
    }
    return result;
}

/// The triangles that `sides` name, by a set.
std::vector<std::uint32_t> named(const Result& result, const MeshTrees::PairSides& sides) {
    std::set<std::uint32_t> out;
    for (const auto& [pair, side] : sides)
        for (const TrianglePair& t : result.pairs[pair].triangles) out.insert(side == 0 ? t.a : t.b);
    return {out.begin(), out.end()};
}

TEST(MeshTrees, PairedTrianglesAreListedSortedWithoutRepeatsEachWay) {
    // Object 0 is side a of pair 0 and side b of pair 1. Each way of listing must give the set of named triangles:
    // side a of one pair (read off its sorted pairs), few named triangles (sorted), many (marked), and the last
    // triangle of the mesh named (the marks' last word).
    std::mt19937 rng(3);
    constexpr std::uint32_t kCount = 10001;
    const MeshTrees::PairSides sideA{{0, 0}}, sideB{{1, 1}}, both{{0, 0}, {1, 1}};
    for (const std::size_t perPair : {std::size_t{5}, kCount / MeshTrees::kSortedFraction / 4, std::size_t{3000}}) {
        Result result = randomPairs(rng, perPair, kCount);
        result.pairs[1].triangles.push_back({kCount + 5, kCount - 1});  // sorted: a is the largest
        for (const MeshTrees::PairSides* sides : {&sideA, &sideB, &both}) {
            std::vector<std::uint32_t> list{123, 7};  // replaced, not appended to
            MeshTrees::listTriangles(result, *sides, kCount, list);
            EXPECT_EQ(list, named(result, *sides)) << perPair << " pairs, " << sides->size() << " sides";
        }
    }
}

}  // namespace
}  // namespace cullide::test
