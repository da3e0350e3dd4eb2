// Bullet's GImpact box-set pair search (btGImpactQuantizedBvh::find_collision), reproduced: the same primitive pairs
// in the same order, with Bullet's float box test at each node pair replaced, wherever rounding cannot matter, by
// integer comparisons on Bullet's own quantization grids.
#pragma once

#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <array>
#include <cstdint>
#include <vector>

namespace cullide {
namespace bullet {

/// A node pair of the two box sets that Bullet's descent keeps (its test passed; the pair of roots, {0, 0}, when the
/// roots overlap on all 15 axes): the descent continues below it, or, for two leaves, it is a primitive pair.
struct NodePair {
    int node0 = 0;
    int node1 = 0;
};

/// A node's box mapped into the other box set's frame and quantized on that set's grid (Bullet's own quantization,
/// rounded outwards): compared as integers with the other set's stored node boxes. `stamp` says for which call it
/// is current (its top bit: the box lies outside the other set's grid, so it meets none of that set's nodes).
struct GridBox {
    std::uint16_t min[3];
    std::uint16_t max[3];
    std::uint32_t stamp;
};

/// Working memory of one thread's pair searches, kept between calls so that a step allocates nothing once warm.
class LeafPairScratch {
public:
    /// Each box set's node boxes on the other set's grid, mapped on first use for a search and kept for the
    /// thread's next part of the same search (the parts of a split search share most of their upper nodes).
    std::vector<GridBox> nodes0, nodes1;
    std::vector<NodePair> stack, front;
    std::uint32_t epoch = 0;    ///< the stamp of the boxes that are current
    std::uint64_t search = 0;   ///< the search they are current for
};

/// One box set's grid coordinates mapped onto the other set's grid (through the frames of the two sets): a node box
/// with grid corners lo, hi lies, on the other grid, within centre a * (lo + hi) / 2 + b, half-extent
/// absA * (hi - lo) / 2 + allowance. The allowance covers Bullet's rounding (the search's slack), this map's own
/// rounding, and one grid step; `sure` is the overlap depth, on the other grid, beyond which a pair of leaves passes
/// Bullet's test whatever the rounding.
struct GridMap {
    btMatrix3x3 a, absA;
    btVector3 b, allowance;
    std::array<int, 3> sure{};
};

/// Bullet's pair search of two box sets (btGImpactQuantizedBvh::find_collision) for one call, reproduced.
///
/// How: Bullet's descent — the root pair tested on all 15 axes, then the same recursion over node pairs, in the same
/// order, each pair tested on the 6 face axes (each box mapped into the other's frame); here a popped pair's
/// children are tested together, without branching on the outcomes — with that test decided in
/// most cases by two integer box overlaps: each set's stored (quantized) node box against the other set's node box
/// mapped onto its grid once per node and search (GridMap), rounded outwards by more than any rounding of Bullet's or
/// the map's. Where either overlap fails, Bullet's test fails; where both hold with the sure depth to spare, it
/// passes; in between (a few percent of the pairs) Bullet's own test (btAABB::overlapping_trans_cache on the two
/// stored boxes) decides. Where the two frames differ by a translation only (Bullet's rotation between them exactly
/// the identity: deforming meshes kept in world space), Bullet's two axis classes test the same axes and the first
/// overlap alone decides (with its sure depth), so the first set's nodes are never mapped. So every node pair is kept
/// or pruned as Bullet's descent keeps or prunes it, rounding included (meshes far from the origin, where Bullet's
/// rounded boxes of a parent and a child can disagree).
///
/// The descent can be cut into parts (split) that run independently, on any threads (the search is read-only;
/// each thread brings its own scratch): their pairs, concatenated in split order, are the whole descent's.
class LeafPairSearch {
public:
    LeafPairSearch(const btGImpactBoxSet& set0, const btTransform& trans0, const btGImpactBoxSet& set1,
                   const btTransform& trans1);
    /// False when Bullet finds no pair at all (an empty set, or the roots apart).
    bool rootsOverlap() const { return m_rootsOverlap; }
    /// Kept node pairs whose descents, in this order, make the whole descent: the root pair alone, or (expanded
    /// level by level in Bullet's order while fewer than `target`) up to about 4 * target pairs below it. None when
    /// the roots are apart.
    void split(std::size_t target, LeafPairScratch& scratch, std::vector<NodePair>& out) const;
    /// The primitive pairs of the descent below the kept pair `start` (the root pair {0, 0}, or one from split),
    /// appended to `interleaved` as prim0, prim1, ... in Bullet's order. From the root pair: the pairs
    /// btGImpactQuantizedBvh::find_collision(&set0, trans0, &set1, trans1, pairSet) finds, so that Bullet's triangle
    /// routine run over them builds the same manifold.
    void descend(const NodePair& start, LeafPairScratch& scratch, std::vector<int>& interleaved) const;
    /// Whether the descent keeps the node pair (node0, node1) below the roots, decided as descend decides it: as
    /// Bullet's test on the two nodes' stored boxes decides it. False when the roots are apart.
    bool keeps(int node0, int node1, LeafPairScratch& scratch) const;

private:
    const btGImpactBoxSet& m_set0;
    const btGImpactBoxSet& m_set1;
    std::uint64_t m_id;  // distinct for every search made (copies share it): the scratches' boxes are per search
    BT_BOX_BOX_TRANSFORM_CACHE m_cache;  // frame 1 -> frame 0, as Bullet computes it
    GridMap m_zeroToOne;  // set 0's grid onto set 1's
    GridMap m_oneToZero;  // set 1's grid onto set 0's
    bool m_rootsOverlap = false;
    bool m_aligned = false;  // Bullet's frame change has exactly the identity rotation: one overlap decides
};

}  // namespace bullet
}  // namespace cullide
