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

LeafPairSearch::LeafPairSearch(const btGImpactBoxSet& set0, const btTransform& trans0, const btGImpactBoxSet& set1,
                               const btTransform& trans1)
    : m_set0(set0), m_set1(set1) {
    if (set0.getNodeCount() == 0 || set1.getNodeCount() == 0) return;
    m_cache.calc_from_homogenic(trans0, trans1);
    btAABB root0, root1;
    set0.getNodeBound(0, root0);
    set1.getNodeBound(0, root1);
    m_rootsOverlap = root0.overlapping_trans_cache(root1, m_cache, true);  // Bullet's root test: all 15 axes
    if (!m_rootsOverlap) return;

    // Frame 0 -> frame 1, inverted from Bullet's map itself: computed again from the two world transforms it would
    // differ from Bullet's by rounding relative to their translations (far from the origin, more than the boxes).
    m_inverse.m_R1to0 = m_cache.m_R1to0.transpose();
    m_inverse.m_T1to0 = -(m_inverse.m_R1to0 * m_cache.m_T1to0);
    m_inverse.calc_absolute_matrix();
    // Every node box lies within its root; mapped coordinates stay within a few times the largest coordinate.
    const btScalar magnitude =
        btMax(btMax(btMax(largestCoordinate(root0.m_min), largestCoordinate(root0.m_max)),
                    btMax(largestCoordinate(root1.m_min), largestCoordinate(root1.m_max))),
              btMax(largestCoordinate(m_cache.m_T1to0), largestCoordinate(m_inverse.m_T1to0)));
    m_slack = btScalar(1024) * SIMD_EPSILON * magnitude;
}

namespace {

/// Bullet's recursion step on one node pair: false when the descent stops there (the boxes apart, or a leaf pair
/// Bullet's test rejects); otherwise a leaf pair is a primitive pair (`leaves` true) or `children` gets the node
/// pairs below in Bullet's order.
struct Step {
    bool keep = false;
    bool leaves = false;
    std::array<NodePair, 4> children{};
    int childCount = 0;
};

Step step(const btGImpactBoxSet& set0, const btGImpactBoxSet& set1, NodeBoxView& view0, NodeBoxView& view1,
          const BT_BOX_BOX_TRANSFORM_CACHE& cache, btScalar slack, const NodePair& p) {
    Step s;
    const std::size_t i0 = view0.at(p.node0);
    const std::size_t i1 = view1.at(p.node1);
    if (!p.root &&
        (!view0.own(i0).has_collision(view1.mapped(i1)) || !view1.own(i1).has_collision(view0.mapped(i0))))
        return s;
    const bool leaf0 = set0.isLeafNode(p.node0);
    const bool leaf1 = set1.isLeafNode(p.node1);
    if (leaf0 && leaf1) {
        // Bullet's leaf test is the same two overlaps up to rounding far below the slack: where both hold with
        // twice the slack to spare it passes for sure; only pairs near its boundary need it.
        const bool surely = overlapsBy(view0.own(i0), view1.mapped(i1), 2 * slack) &&
                            overlapsBy(view1.own(i1), view0.mapped(i0), 2 * slack);
        s.keep = p.root || surely || view0.own(i0).overlapping_trans_cache(view1.own(i1), cache, false);
        s.leaves = true;
        return s;
    }
    s.keep = true;
    const auto add = [&s](int n0, int n1) { s.children[static_cast<std::size_t>(s.childCount++)] = {n0, n1, false}; };
    if (leaf0) {
        add(p.node0, set1.getLeftNode(p.node1));
        add(p.node0, set1.getRightNode(p.node1));
    } else if (leaf1) {
        add(set0.getLeftNode(p.node0), p.node1);
        add(set0.getRightNode(p.node0), p.node1);
    } else {
        const int left0 = set0.getLeftNode(p.node0), right0 = set0.getRightNode(p.node0);
        const int left1 = set1.getLeftNode(p.node1), right1 = set1.getRightNode(p.node1);
        add(left0, left1);
        add(left0, right1);
        add(right0, left1);
        add(right0, right1);
    }
    return s;
}

}  // namespace

void LeafPairSearch::split(std::size_t target, LeafPairScratch& scratch, std::vector<NodePair>& out) const {
    out.clear();
    if (!m_rootsOverlap) return;
    out.push_back({0, 0, true});
    const std::uint32_t epoch = nextEpoch(scratch);
    NodeBoxView view0(m_set0, m_inverse, m_slack, scratch.nodes0, epoch);
    NodeBoxView view1(m_set1, m_cache, m_slack, scratch.nodes1, epoch);
    std::vector<NodePair>& next = scratch.front;
    bool expanded = true;
    while (out.size() < target && expanded) {
        // One level: every internal pair the descent keeps is replaced by its children, in place (Bullet's order
        // is preserved); leaf pairs stay (their descent is their own test).
        next.clear();
        expanded = false;
        for (const NodePair& p : out) {
            if (m_set0.isLeafNode(p.node0) && m_set1.isLeafNode(p.node1)) {
                next.push_back(p);
                continue;
            }
            const Step s = step(m_set0, m_set1, view0, view1, m_cache, m_slack, p);
            if (!s.keep) continue;
            next.insert(next.end(), s.children.begin(), s.children.begin() + s.childCount);
            expanded = true;
        }
        out.swap(next);
    }
}

void LeafPairSearch::descend(const NodePair& start, LeafPairScratch& scratch, std::vector<int>& interleaved) const {
    if (!m_rootsOverlap) return;
    const std::uint32_t epoch = nextEpoch(scratch);
    NodeBoxView view0(m_set0, m_inverse, m_slack, scratch.nodes0, epoch);
    NodeBoxView view1(m_set1, m_cache, m_slack, scratch.nodes1, epoch);
    // Bullet's recursion, with an explicit stack: children pushed in reverse so that they are visited in its order.
    std::vector<NodePair>& stack = scratch.stack;
    stack.clear();
    stack.push_back(start);
    while (!stack.empty()) {
        const NodePair p = stack.back();
        stack.pop_back();
        const Step s = step(m_set0, m_set1, view0, view1, m_cache, m_slack, p);
        if (!s.keep) continue;
        if (s.leaves) {
            interleaved.push_back(m_set0.getNodeData(p.node0));
            interleaved.push_back(m_set1.getNodeData(p.node1));
            continue;
        }
        for (int c = s.childCount; c-- > 0;) stack.push_back(s.children[static_cast<std::size_t>(c)]);
    }
}

}  // namespace detail
}  // namespace cullide
