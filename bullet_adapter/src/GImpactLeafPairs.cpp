#include "GImpactLeafPairs.h"

#include <BulletCollision/Gimpact/btBoxCollision.h>

#include <algorithm>

namespace cullide {
namespace detail {
namespace {

btScalar largestCoordinate(const btVector3& v) {
    const btVector3 a = v.absolute();
    return a[a.maxAxis()];
}

/// The box around `box` mapped by `cache` into the other frame (centre by the rotation and translation, extents by
/// the absolute rotation, as Bullet's box test maps them), grown by `slack` on every side.
btAABB mappedBox(const btAABB& box, const BT_BOX_BOX_TRANSFORM_CACHE& cache, btScalar slack) {
    btVector3 centre, extent;
    box.get_center_extend(centre, extent);
    btVector3 c, e;
    for (int i = 0; i < 3; ++i) {
        c[i] = cache.m_R1to0[i].dot(centre) + cache.m_T1to0[i];
        e[i] = cache.m_AR[i].dot(extent) + slack;
    }
    btAABB out;
    out.m_min = c - e;
    out.m_max = c + e;
    return out;
}

/// One box set's node boxes for one call, computed on first use.
class NodeBoxView {
public:
    NodeBoxView(const btGImpactBoxSet& set, const BT_BOX_BOX_TRANSFORM_CACHE& toOther, btScalar slack,
                LeafPairScratch::NodeBoxes& boxes, std::uint32_t epoch)
        : m_set(set), m_toOther(toOther), m_slack(slack), m_boxes(boxes), m_epoch(epoch) {
        const std::size_t n = static_cast<std::size_t>(set.getNodeCount());
        if (m_boxes.stamp.size() < n) {
            m_boxes.stamp.resize(n, 0u);
            m_boxes.own.resize(n);
            m_boxes.mapped.resize(n);
        }
    }
    /// Makes the boxes of `node` current; returns its index into own / mapped.
    std::size_t at(int node) {
        const std::size_t i = static_cast<std::size_t>(node);
        if (m_boxes.stamp[i] != m_epoch) {
            m_set.getNodeBound(node, m_boxes.own[i]);
            m_boxes.mapped[i] = mappedBox(m_boxes.own[i], m_toOther, m_slack);
            m_boxes.stamp[i] = m_epoch;
        }
        return i;
    }
    const btAABB& own(std::size_t i) const { return m_boxes.own[i]; }
    const btAABB& mapped(std::size_t i) const { return m_boxes.mapped[i]; }

private:
    const btGImpactBoxSet& m_set;
    const BT_BOX_BOX_TRANSFORM_CACHE& m_toOther;
    btScalar m_slack;
    LeafPairScratch::NodeBoxes& m_boxes;
    std::uint32_t m_epoch;
};

/// True when `a` and `b` overlap with `depth` to spare on every axis (`b` shrunk by `depth` still meets `a`).
bool overlapsBy(const btAABB& a, const btAABB& b, btScalar depth) {
    for (int k = 0; k < 3; ++k)
        if (a.m_min[k] > b.m_max[k] - depth || a.m_max[k] < b.m_min[k] + depth) return false;
    return true;
}

std::uint32_t nextEpoch(LeafPairScratch& scratch) {
    if (++scratch.epoch == 0) {  // wrapped: no stamp may look current
        std::fill(scratch.nodes0.stamp.begin(), scratch.nodes0.stamp.end(), 0u);
        std::fill(scratch.nodes1.stamp.begin(), scratch.nodes1.stamp.end(), 0u);
        scratch.epoch = 1;
    }
    return scratch.epoch;
}

}  // namespace

void findLeafPairs(const btGImpactBoxSet& set0, const btTransform& trans0, const btGImpactBoxSet& set1,
                   const btTransform& trans1, LeafPairScratch& scratch, std::vector<int>& interleaved) {
    if (set0.getNodeCount() == 0 || set1.getNodeCount() == 0) return;
    BT_BOX_BOX_TRANSFORM_CACHE cache;  // frame 1 -> frame 0, as Bullet computes it
    cache.calc_from_homogenic(trans0, trans1);
    btAABB root0, root1;
    set0.getNodeBound(0, root0);
    set1.getNodeBound(0, root1);
    if (!root0.overlapping_trans_cache(root1, cache, true)) return;  // Bullet's root test: all 15 axes

    // Frame 0 -> frame 1, inverted from Bullet's map itself: computed again from the two world transforms it would
    // differ from Bullet's by rounding relative to their translations (far from the origin, more than the boxes).
    BT_BOX_BOX_TRANSFORM_CACHE inverse;
    inverse.m_R1to0 = cache.m_R1to0.transpose();
    inverse.m_T1to0 = -(inverse.m_R1to0 * cache.m_T1to0);
    inverse.calc_absolute_matrix();
    // Every node box lies within its root; mapped coordinates stay within a few times the largest coordinate.
    const btScalar magnitude =
        btMax(btMax(btMax(largestCoordinate(root0.m_min), largestCoordinate(root0.m_max)),
                    btMax(largestCoordinate(root1.m_min), largestCoordinate(root1.m_max))),
              btMax(largestCoordinate(cache.m_T1to0), largestCoordinate(inverse.m_T1to0)));
    const btScalar slack = btScalar(1024) * SIMD_EPSILON * magnitude;
    const std::uint32_t epoch = nextEpoch(scratch);
    NodeBoxView view0(set0, inverse, slack, scratch.nodes0, epoch);
    NodeBoxView view1(set1, cache, slack, scratch.nodes1, epoch);

    // Bullet's recursion, with an explicit stack: children pushed in reverse so that they are visited in its order.
    std::vector<std::array<int, 2>>& stack = scratch.stack;
    stack.clear();
    stack.push_back({0, 0});
    bool root = true;
    while (!stack.empty()) {
        const int node0 = stack.back()[0];
        const int node1 = stack.back()[1];
        stack.pop_back();
        const std::size_t i0 = view0.at(node0);
        const std::size_t i1 = view1.at(node1);
        if (!root && (!view0.own(i0).has_collision(view1.mapped(i1)) ||
                      !view1.own(i1).has_collision(view0.mapped(i0))))
            continue;
        const bool leaf0 = set0.isLeafNode(node0);
        const bool leaf1 = set1.isLeafNode(node1);
        if (leaf0 && leaf1) {
            // Bullet's leaf test is the same two overlaps up to rounding far below the slack: where both hold with
            // twice the slack to spare it passes for sure; only pairs near its boundary need it.
            const bool surely = overlapsBy(view0.own(i0), view1.mapped(i1), 2 * slack) &&
                                overlapsBy(view1.own(i1), view0.mapped(i0), 2 * slack);
            if (root || surely || view0.own(i0).overlapping_trans_cache(view1.own(i1), cache, false)) {
                interleaved.push_back(set0.getNodeData(node0));
                interleaved.push_back(set1.getNodeData(node1));
            }
        } else if (leaf0) {
            stack.push_back({node0, set1.getRightNode(node1)});
            stack.push_back({node0, set1.getLeftNode(node1)});
        } else if (leaf1) {
            stack.push_back({set0.getRightNode(node0), node1});
            stack.push_back({set0.getLeftNode(node0), node1});
        } else {
            const int left0 = set0.getLeftNode(node0), right0 = set0.getRightNode(node0);
            const int left1 = set1.getLeftNode(node1), right1 = set1.getRightNode(node1);
            stack.push_back({right0, right1});
            stack.push_back({right0, left1});
            stack.push_back({left0, right1});
            stack.push_back({left0, left1});
        }
        root = false;
    }
}

}  // namespace detail
}  // namespace cullide
