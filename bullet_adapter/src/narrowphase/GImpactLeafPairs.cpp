#include "narrowphase/GImpactLeafPairs.h"

#include <BulletCollision/Gimpact/btBoxCollision.h>

#include <algorithm>
#include <atomic>
#include <cmath>

// The descent's per-pair steps are inlined into its loop whatever the compiler's estimate (Bullet's
// SIMD_FORCE_INLINE is plain `inline` on Linux): a call per node pair costs a quarter of the search.
#if defined(__GNUC__) || defined(__clang__)
#define CULLIDE_ALWAYS_INLINE inline __attribute__((always_inline))
#elif defined(_MSC_VER)
#define CULLIDE_ALWAYS_INLINE __forceinline
#else
#define CULLIDE_ALWAYS_INLINE inline
#endif

namespace cullide {
namespace bullet {
namespace {

btScalar largestCoordinate(const btVector3& v) {
    const btVector3 a = v.absolute();
    return a[a.maxAxis()];
}

constexpr std::uint32_t kOutside = 0x80000000u;  // GridBox::stamp: the box lies outside the other set's grid
constexpr btScalar kTop = btScalar(65535);        // the largest grid coordinate

/// `node`'s box on the other set's grid by `map`, rounded outwards; false when it lies beyond that grid on some axis
/// (it meets none of that set's node boxes). A NaN coordinate spans the grid.
bool mapNode(const BT_QUANTIZED_BVH_NODE& node, const GridMap& map, GridBox& out) {
    const btVector3 lo(node.m_quantizedAabbMin[0], node.m_quantizedAabbMin[1], node.m_quantizedAabbMin[2]);
    const btVector3 hi(node.m_quantizedAabbMax[0], node.m_quantizedAabbMax[1], node.m_quantizedAabbMax[2]);
    const btVector3 centre = (lo + hi) * btScalar(0.5);
    const btVector3 extent = (hi - lo) * btScalar(0.5);
    for (int k = 0; k < 3; ++k) {
        const btScalar c = map.a[k].dot(centre) + map.b[k];
        const btScalar e = map.absA[k].dot(extent) + map.allowance[k];
        const btScalar min = c - e, max = c + e;
        if (min > kTop || max < 0) return false;
        out.min[k] = min > 0 ? static_cast<std::uint16_t>(min) : std::uint16_t(0);  // truncation: the floor
        out.max[k] = max < kTop ? static_cast<std::uint16_t>(static_cast<std::uint16_t>(max) + 1)
                                : static_cast<std::uint16_t>(kTop);
    }
    return true;
}

/// Whether `node`'s stored box meets `box` with `depth` steps to spare on every axis.
CULLIDE_ALWAYS_INLINE bool overlapsBy(const BT_QUANTIZED_BVH_NODE& node, const GridBox& box,
                                      const std::array<int, 3>& depth) {
    for (int k = 0; k < 3; ++k)
        if (int(node.m_quantizedAabbMax[k]) - int(box.min[k]) < depth[static_cast<std::size_t>(k)] ||
            int(box.max[k]) - int(node.m_quantizedAabbMin[k]) < depth[static_cast<std::size_t>(k)])
            return false;
    return true;
}

/// Whether `node`'s stored box meets `box` (false when `box` lies outside the grid). Evaluated without branches: the
/// outcome is data, not a pattern a branch predictor could learn.
CULLIDE_ALWAYS_INLINE bool overlaps(const BT_QUANTIZED_BVH_NODE& node, const GridBox& box) {
    return ((box.stamp & kOutside) == 0) & (node.m_quantizedAabbMin[0] <= box.max[0]) &
           (node.m_quantizedAabbMax[0] >= box.min[0]) & (node.m_quantizedAabbMin[1] <= box.max[1]) &
           (node.m_quantizedAabbMax[1] >= box.min[1]) & (node.m_quantizedAabbMin[2] <= box.max[2]) &
           (node.m_quantizedAabbMax[2] >= box.min[2]);
}

/// One box set's node boxes on the other set's grid for one search, computed on first use.
class NodeGridView {
public:
    NodeGridView(const BT_QUANTIZED_BVH_NODE* nodes, int nodeCount, const GridMap& map, std::vector<GridBox>& boxes,
                 std::uint32_t epoch)
        : m_nodes(nodes), m_map(map), m_boxes(boxes), m_epoch(epoch) {
        const std::size_t n = static_cast<std::size_t>(nodeCount);
        if (m_boxes.size() < n) m_boxes.resize(n, GridBox{{0, 0, 0}, {0, 0, 0}, 0u});
    }
    /// `node`'s box on the other set's grid, mapped on first use in the search (the stamp's top bit: it lies outside
    /// that grid).
    CULLIDE_ALWAYS_INLINE const GridBox& at(int node) {
        GridBox& box = m_boxes[static_cast<std::size_t>(node)];
        if ((box.stamp & ~kOutside) != m_epoch)
            box.stamp = m_epoch | (mapNode(m_nodes[node], m_map, box) ? 0u : kOutside);
        return box;
    }

private:
    const BT_QUANTIZED_BVH_NODE* m_nodes;
    const GridMap& m_map;
    std::vector<GridBox>& m_boxes;
    std::uint32_t m_epoch;
};

/// A box set's quantization grid as Bullet quantizes its node boxes: grid = (point - offset) * scale. Bullet keeps
/// it in protected members, read here through the classes' own pointer-to-member rules.
struct QuantizationGrid {
    btVector3 offset;
    btVector3 scale;
};
struct TreeAccess : btQuantizedBvhTree {
    static QuantizationGrid grid(const btQuantizedBvhTree& tree) {
        return {(tree.*(&TreeAccess::m_global_bound)).m_min, tree.*(&TreeAccess::m_bvhQuantization)};
    }
};
struct BoxSetAccess : btGImpactQuantizedBvh {
    static QuantizationGrid grid(const btGImpactQuantizedBvh& set) {
        return TreeAccess::grid(set.*(&BoxSetAccess::m_box_tree));
    }
};

/// The map from grid `from` (frame F) onto grid `to` (frame T) for points mapped by x_T = rotation * x_F +
/// translation; `slack` (in frame units) covers Bullet's own rounding and the widening of its test.
GridMap gridMap(const QuantizationGrid& from, const btMatrix3x3& rotation, const btVector3& translation,
                const QuantizationGrid& to, btScalar slack) {
    // Bullet unquantizes q as q / scale + offset: on `to`'s grid the point is
    // to.scale * (rotation * (q / from.scale + from.offset) + translation - to.offset).
    GridMap map;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) map.a[i][j] = to.scale[i] * rotation[i][j] / from.scale[j];
    map.absA = map.a.absolute();
    map.b = to.scale * (rotation * from.offset + translation - to.offset);
    for (int i = 0; i < 3; ++i) {
        // This map's rounding: a few units in the last place of the largest term (grid coordinates up to kTop).
        const btScalar terms = (map.absA[i][0] + map.absA[i][1] + map.absA[i][2]) * kTop + btFabs(map.b[i]);
        map.allowance[i] = slack * to.scale[i] + 32 * SIMD_EPSILON * terms + 1;
        const btScalar sure = std::ceil(3 * map.allowance[i]) + 1;
        map.sure[static_cast<std::size_t>(i)] = sure < btScalar(1 << 20) ? static_cast<int>(sure) : (1 << 20);
    }
    return map;
}

/// The epoch of `scratch`'s node boxes for the search `searchId`: the current one when they were mapped for that
/// search (the thread's previous part of the same search), a new one otherwise.
std::uint32_t epochFor(std::uint64_t searchId, LeafPairScratch& scratch) {
    if (scratch.search == searchId) return scratch.epoch;
    scratch.search = searchId;
    if (++scratch.epoch == kOutside) {  // wrapped: no stamp may look current
        for (GridBox& box : scratch.nodes0) box.stamp = 0;
        for (GridBox& box : scratch.nodes1) box.stamp = 0;
        scratch.epoch = 1;
    }
    return scratch.epoch;
}

/// Whether `m` is exactly the identity.
bool isIdentity(const btMatrix3x3& m) {
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (m[i][j] != (i == j ? btScalar(1) : btScalar(0))) return false;
    return true;
}

/// Identifies a search for the scratches' node boxes (never 0: a new scratch serves none).
std::uint64_t newSearchId() {
    static std::atomic<std::uint64_t> last{0};
    return last.fetch_add(1, std::memory_order_relaxed) + 1;
}

}  // namespace

LeafPairSearch::LeafPairSearch(const btGImpactBoxSet& set0, const btTransform& trans0, const btGImpactBoxSet& set1,
                               const btTransform& trans1)
    : m_set0(set0), m_set1(set1), m_id(newSearchId()) {
    if (set0.getNodeCount() == 0 || set1.getNodeCount() == 0) return;
    m_cache.calc_from_homogenic(trans0, trans1);
    btAABB root0, root1;
    set0.getNodeBound(0, root0);
    set1.getNodeBound(0, root1);
    m_rootsOverlap = root0.overlapping_trans_cache(root1, m_cache, true);  // Bullet's root test: all 15 axes
    if (!m_rootsOverlap) return;

    // Frame 0 -> frame 1, inverted from Bullet's map itself: computed again from the two world transforms it would
    // differ from Bullet's by rounding relative to their translations (far from the origin, more than the boxes).
    const btMatrix3x3 inverse = m_cache.m_R1to0.transpose();
    const btVector3 inverseT = -(inverse * m_cache.m_T1to0);
    // Every node box lies within its root; mapped coordinates stay within a few times the largest coordinate.
    const btScalar magnitude =
        btMax(btMax(btMax(largestCoordinate(root0.m_min), largestCoordinate(root0.m_max)),
                    btMax(largestCoordinate(root1.m_min), largestCoordinate(root1.m_max))),
              btMax(largestCoordinate(m_cache.m_T1to0), largestCoordinate(inverseT)));
    // Bullet's rounding: its test (dequantized corners, centres and extents, one dot product for the frame change,
    // a second one in the second set's frame on the first's result) rounds each step by at most half a unit in the
    // last place of terms up to a few times `magnitude`; summed over the steps that is under 60 units of
    // `magnitude`'s last place, and the allowance is twice that. (Measured: the tests' poses, far from the origin
    // included, see no wrong decision down to 4 units, and many below 2.)
    const btScalar rounding = btScalar(128) * SIMD_EPSILON * magnitude;
    // Bullet's widening: its absolute rotation (m_AR) is |R| + 1e-6, which widens the box mapped by it by 1e-6 times
    // the sum of its half-extents, at most its root's (in double precision too, where it exceeds the rounding).
    const auto widening = [](const btAABB& root) {
        const btVector3 half = (root.m_max - root.m_min) * btScalar(0.5);
        return btScalar(2e-6) * (btFabs(half[0]) + btFabs(half[1]) + btFabs(half[2]));
    };
    const QuantizationGrid grid0 = BoxSetAccess::grid(set0), grid1 = BoxSetAccess::grid(set1);
    m_zeroToOne = gridMap(grid0, inverse, inverseT, grid1, rounding + widening(root0));
    m_oneToZero = gridMap(grid1, m_cache.m_R1to0, m_cache.m_T1to0, grid0, rounding + widening(root1));
    // Frames that differ by a translation only (deforming meshes kept in world space, bodies that do not turn): with
    // m_R1to0 exactly the identity, both of Bullet's axis classes test the same three axes, class I on box 1
    // widened by 1e-6 of its extents and class II on box 0 widened likewise (each more permissive than the exact
    // test), so one overlap on set 0's grid, with its allowance (which covers the widening of box 1) and sure depth,
    // decides the pair as both would.
    m_aligned = isIdentity(m_cache.m_R1to0);
}

namespace {

/// What one descent reads: the two sets, their node arrays, and their node boxes on each other's grid.
struct Descent {
    const btGImpactBoxSet& set0;
    const btGImpactBoxSet& set1;
    const BT_QUANTIZED_BVH_NODE* nodes0;
    const BT_QUANTIZED_BVH_NODE* nodes1;
    NodeGridView view0;  // set 0's nodes on set 1's grid
    NodeGridView view1;  // set 1's nodes on set 0's grid
    const BT_BOX_BOX_TRANSFORM_CACHE& cache;
    const std::array<int, 3>& sure0;  // on set 0's grid
    const std::array<int, 3>& sure1;  // on set 1's grid
    bool aligned;                     // the frames differ by a translation only (LeafPairSearch::m_aligned)
};

/// Bullet's test of a node pair below the roots, on the two nodes' stored boxes.
bool bulletTest(const Descent& d, int node0, int node1) {
    btAABB box0, box1;
    d.set0.getNodeBound(node0, box0);
    d.set1.getNodeBound(node1, box1);
    return box0.overlapping_trans_cache(box1, d.cache, false);
}

/// Whether Bullet's descent keeps the node pair (node0, node1) below the roots: Bullet's test on it (the 6 face axes
/// of btAABB::overlapping_trans_cache on its rounded boxes) fails where the grid boxes are apart, and passes where
/// they overlap with room to spare for its rounding; only pairs near its boundary need it. For aligned frames the
/// overlap on set 0's grid alone decides (the two axis classes are the same axes).
CULLIDE_ALWAYS_INLINE bool kept(Descent& d, int node0, int node1) {
    const BT_QUANTIZED_BVH_NODE& n0 = d.nodes0[node0];
    const BT_QUANTIZED_BVH_NODE& n1 = d.nodes1[node1];
    const GridBox& on0 = d.view1.at(node1);  // node 1 on set 0's grid
    if (!overlaps(n0, on0)) return false;  // node 0 need not be mapped (many pairs end here)
    if (d.aligned) return overlapsBy(n0, on0, d.sure0) || bulletTest(d, node0, node1);
    const GridBox& on1 = d.view0.at(node0);  // node 0 on set 1's grid
    if (!overlaps(n1, on1)) return false;
    if (overlapsBy(n0, on0, d.sure0) && overlapsBy(n1, on1, d.sure1)) return true;
    return bulletTest(d, node0, node1);
}

/// Puts (node0, node1) on top of `stack` and keeps it there when the descent keeps the pair (no branch on it).
CULLIDE_ALWAYS_INLINE void pushIfKept(Descent& d, int node0, int node1, NodePair* stack, std::size_t& top) {
    stack[top] = {node0, node1};
    top += kept(d, node0, node1) ? 1 : 0;
}

/// The kept pairs below the kept pair `p`, pushed so that they pop in Bullet's order: (left0, left1), (left0, right1),
/// (right0, left1), (right0, right1), a leaf standing for itself. `stack` has room for four more; `p` is not a leaf
/// pair.
CULLIDE_ALWAYS_INLINE void pushKeptChildren(Descent& d, const NodePair& p, NodePair* stack, std::size_t& top) {
    const bool leaf0 = d.nodes0[p.node0].isLeafNode();
    const bool leaf1 = d.nodes1[p.node1].isLeafNode();
    if (leaf0) {
        pushIfKept(d, p.node0, d.set1.getRightNode(p.node1), stack, top);
        pushIfKept(d, p.node0, d.set1.getLeftNode(p.node1), stack, top);
    } else if (leaf1) {
        pushIfKept(d, d.set0.getRightNode(p.node0), p.node1, stack, top);
        pushIfKept(d, d.set0.getLeftNode(p.node0), p.node1, stack, top);
    } else {
        const int left0 = d.set0.getLeftNode(p.node0), right0 = d.set0.getRightNode(p.node0);
        const int left1 = d.set1.getLeftNode(p.node1), right1 = d.set1.getRightNode(p.node1);
        pushIfKept(d, right0, right1, stack, top);
        pushIfKept(d, right0, left1, stack, top);
        pushIfKept(d, left0, right1, stack, top);
        pushIfKept(d, left0, left1, stack, top);
    }
}

bool isLeafPair(const Descent& d, const NodePair& p) {
    return d.nodes0[p.node0].isLeafNode() && d.nodes1[p.node1].isLeafNode();
}

/// A descent over the two sets for the search `searchId`, with the scratch's node boxes current for it.
Descent descentOf(std::uint64_t searchId, const btGImpactBoxSet& set0, const btGImpactBoxSet& set1,
                  const BT_BOX_BOX_TRANSFORM_CACHE& cache, const GridMap& zeroToOne, const GridMap& oneToZero,
                  bool aligned, LeafPairScratch& scratch) {
    const std::uint32_t epoch = epochFor(searchId, scratch);
    const BT_QUANTIZED_BVH_NODE* nodes0 = set0.get_node_pointer();
    const BT_QUANTIZED_BVH_NODE* nodes1 = set1.get_node_pointer();
    return {set0,
            set1,
            nodes0,
            nodes1,
            NodeGridView(nodes0, set0.getNodeCount(), zeroToOne, scratch.nodes0, epoch),
            NodeGridView(nodes1, set1.getNodeCount(), oneToZero, scratch.nodes1, epoch),
            cache,
            oneToZero.sure,
            zeroToOne.sure,
            aligned};
}

}  // namespace

void LeafPairSearch::split(std::size_t target, LeafPairScratch& scratch, std::vector<NodePair>& out) const {
    out.clear();
    if (!m_rootsOverlap) return;
    out.push_back({0, 0});
    Descent d = descentOf(m_id, m_set0, m_set1, m_cache, m_zeroToOne, m_oneToZero, m_aligned, scratch);
    std::vector<NodePair>& next = scratch.front;
    bool expanded = true;
    while (out.size() < target && expanded) {
        // One level: every kept internal pair is replaced by its kept children, in Bullet's order (pushed last to
        // first, then reversed in place); leaf pairs stay.
        next.clear();
        expanded = false;
        for (const NodePair& p : out) {
            if (isLeafPair(d, p)) {
                next.push_back(p);
                continue;
            }
            const std::size_t first = next.size();
            next.resize(first + 4);
            std::size_t top = first;
            pushKeptChildren(d, p, next.data(), top);
            next.resize(top);
            std::reverse(next.begin() + static_cast<std::ptrdiff_t>(first), next.end());
            expanded = true;
        }
        out.swap(next);
    }
}

void LeafPairSearch::descend(const NodePair& start, LeafPairScratch& scratch, std::vector<int>& interleaved) const {
    if (!m_rootsOverlap) return;
    Descent d = descentOf(m_id, m_set0, m_set1, m_cache, m_zeroToOne, m_oneToZero, m_aligned, scratch);
    // Bullet's recursion with an explicit stack of kept pairs: each popped internal pair's children are all tested
    // at once and the kept ones pushed last to first, so that they pop in Bullet's order.
    std::vector<NodePair>& stack = scratch.stack;
    if (stack.size() < 64) stack.resize(64);
    std::size_t top = 0;
    stack[top++] = start;
    while (top != 0) {
        const NodePair p = stack[--top];
        if (isLeafPair(d, p)) {
            interleaved.push_back(d.nodes0[p.node0].getDataIndex());
            interleaved.push_back(d.nodes1[p.node1].getDataIndex());
            continue;
        }
        if (stack.size() - top < 4) stack.resize(2 * stack.size());
        pushKeptChildren(d, p, stack.data(), top);
    }
}

bool LeafPairSearch::keeps(int node0, int node1, LeafPairScratch& scratch) const {
    if (!m_rootsOverlap) return false;
    Descent d = descentOf(m_id, m_set0, m_set1, m_cache, m_zeroToOne, m_oneToZero, m_aligned, scratch);
    return kept(d, node0, node1);
}

}  // namespace bullet
}  // namespace cullide
