// Bullet's GImpact box-set pair search (btGImpactQuantizedBvh::find_collision), reproduced: the same primitive pairs
// in the same order, found from the leaves that can take part instead of by descending both trees pair by pair.
#pragma once

#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <array>
#include <cstdint>
#include <vector>

namespace cullide {
namespace detail {

/// Working memory of findLeafPairs, kept between calls so that a step allocates nothing once warm.
class LeafPairScratch {
public:
    /// Node boxes of one box set for one call: its own (dequantized) and mapped into the other set's frame, computed on
    /// first use.
    struct NodeBoxes {
        std::vector<btAABB> own, mapped;
        std::vector<std::uint32_t> stamp;
    };
    NodeBoxes nodes0, nodes1;
    std::vector<std::array<int, 2>> stack;
    std::uint32_t epoch = 0;
};

/// The primitive pairs that btGImpactQuantizedBvh::find_collision(&set0, trans0, &set1, trans1, pairSet) finds,
/// appended to `interleaved` as prim0, prim1, ... in Bullet's order, so that Bullet's triangle routine run over them
/// builds the same manifold.
///
/// How: Bullet's descent — the root pair tested on all 15 axes, then the same recursion over node pairs, in the same
/// order — with Bullet's box test (the 6 face axes, each box mapped into the other's frame per node pair) replaced
/// by two plain box overlaps against boxes mapped once per node and call (set 1's node boxes in set 0's frame, set
/// 0's in set 1's, slightly grown so that rounding never prunes a pair Bullet keeps). A leaf pair is then decided by
/// Bullet's own test (btAABB::overlapping_trans_cache on the two leaf boxes). Bullet's descent also prunes by its own
/// test on the ancestor pairs on the way down; that test passes whenever the leaves' does (the boxes contain the
/// leaves'), up to float rounding between boxes that contain each other, which is not replicated.
void findLeafPairs(const btGImpactBoxSet& set0, const btTransform& trans0, const btGImpactBoxSet& set1,
                   const btTransform& trans1, LeafPairScratch& scratch, std::vector<int>& interleaved);

}  // namespace detail
}  // namespace cullide
