// Bullet's GImpact box-set pair search (btGImpactQuantizedBvh::find_collision), reproduced: the same primitive pairs
// in the same order, found from the leaves that can take part instead of by descending both trees pair by pair.
#pragma once

#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <array>
#include <cstdint>
#include <vector>

namespace cullide {
namespace detail {

/// A node pair of the two box sets where Bullet's descent continues; `root`: the pair of roots, which Bullet has
/// already tested on all 15 axes (a root pair of two leaves is a primitive pair without further test).
struct NodePair {
    int node0 = 0;
    int node1 = 0;
    bool root = false;
};

/// Working memory of one thread's pair searches, kept between calls so that a step allocates nothing once warm.
class LeafPairScratch {
public:
    /// Node boxes of one box set for one call: its own (dequantized) and mapped into the other set's frame, computed on
    /// first use.
    struct NodeBoxes {
        std::vector<btAABB> own, mapped;
        std::vector<std::uint32_t> stamp;
    };
    NodeBoxes nodes0, nodes1;
    std::vector<NodePair> stack, front;
    std::uint32_t epoch = 0;
};

/// Bullet's pair search of two box sets (btGImpactQuantizedBvh::find_collision) for one call, reproduced.
///
/// How: Bullet's descent — the root pair tested on all 15 axes, then the same recursion over node pairs, in the same
/// order — with Bullet's box test (the 6 face axes, each box mapped into the other's frame per node pair) replaced
/// by two plain box overlaps against boxes mapped once per node and call (set 1's node boxes in set 0's frame, set
/// 0's in set 1's, slightly grown so that rounding never prunes a pair Bullet keeps). A leaf pair is then decided by
/// Bullet's own test (btAABB::overlapping_trans_cache on the two leaf boxes). Bullet's descent also prunes by its own
/// test on the ancestor pairs on the way down; that test passes whenever the leaves' does (the boxes contain the
/// leaves'), up to float rounding between boxes that contain each other, which is not replicated.
///
/// The descent can be cut into parts (split) that run independently, on any threads (the search is read-only;
/// each thread brings its own scratch): their pairs, concatenated in split order, are the whole descent's.
class LeafPairSearch {
public:
    LeafPairSearch(const btGImpactBoxSet& set0, const btTransform& trans0, const btGImpactBoxSet& set1,
                   const btTransform& trans1);
    /// False when Bullet finds no pair at all (an empty set, or the roots apart).
    bool rootsOverlap() const { return m_rootsOverlap; }
    /// The node pairs whose descents, in this order, make the whole descent: the root pair alone, or (expanded
    /// level by level in Bullet's order while fewer than `target`) up to about 4 * target pairs below it.
    void split(std::size_t target, LeafPairScratch& scratch, std::vector<NodePair>& out) const;
    /// The primitive pairs of the descent from `start`, appended to `interleaved` as prim0, prim1, ... in Bullet's
    /// order. From the root pair ({0, 0, true}): the pairs btGImpactQuantizedBvh::find_collision(&set0, trans0,
    /// &set1, trans1, pairSet) finds, so that Bullet's triangle routine run over them builds the same manifold.
    void descend(const NodePair& start, LeafPairScratch& scratch, std::vector<int>& interleaved) const;

private:
    const btGImpactBoxSet& m_set0;
    const btGImpactBoxSet& m_set1;
    BT_BOX_BOX_TRANSFORM_CACHE m_cache;    // frame 1 -> frame 0, as Bullet computes it
    BT_BOX_BOX_TRANSFORM_CACHE m_inverse;  // frame 0 -> frame 1, inverted from m_cache
    btScalar m_slack = 0;
    bool m_rootsOverlap = false;
};

}  // namespace detail
}  // namespace cullide
