// The leaf node of each primitive of GImpact box sets, so that a culled mesh-mesh pair's surviving triangle pairs
// are tested exactly as Bullet's box-set traversal tests them (GImpactMeshMeshAlgorithm).
#pragma once

#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace cullide::bullet {

/// The leaf node of each primitive of a GImpact box set (btGImpactQuantizedBvh), so a surviving triangle pair can be
/// tested exactly as Bullet's BVH traversal tests it. Entries are checked on every lookup (the leaf must still hold
/// the primitive) and rebuilt when a box set was rebuilt (updateBound after deforming) or its address reused; box
/// sets unused for kKeepDispatches dispatches (deleted shapes) are dropped.
class GImpactLeafIndex {
public:
    /// Called at the start of every dispatch: drops the entries of box sets no longer used.
    void beginDispatch() {
        ++m_epoch;
        for (auto it = m_leaves.begin(); it != m_leaves.end();) {
            if (it->second.lastUse + kKeepDispatches < m_epoch)
                it = m_leaves.erase(it);
            else
                ++it;
        }
    }
    /// The leaf node of each primitive of `set`, as last built (stable until the next beginDispatch): check an
    /// entry with `leafOf`.
    std::vector<int>& leavesOf(const btGImpactBoxSet& set) {
        Entry& e = m_leaves[&set];
        e.lastUse = m_epoch;
        return e.leaves;
    }
    /// The leaf of `prim` (rebuilding `leaves` once if it is stale), or -1 when the set has none.
    static int leafOf(const btGImpactBoxSet& set, std::vector<int>& leaves, int prim) {
        if (!holds(set, leaves, prim)) {
            rebuild(set, leaves);
            if (!holds(set, leaves, prim)) return -1;
        }
        return leaves[static_cast<std::size_t>(prim)];
    }

private:
    static constexpr std::uint64_t kKeepDispatches = 60;
    struct Entry {
        std::vector<int> leaves;
        std::uint64_t lastUse = 0;
    };

    static bool holds(const btGImpactBoxSet& set, const std::vector<int>& leaves, int prim) {
        if (prim < 0 || static_cast<std::size_t>(prim) >= leaves.size()) return false;
        const int node = leaves[static_cast<std::size_t>(prim)];
        return node >= 0 && node < set.getNodeCount() && set.isLeafNode(node) && set.getNodeData(node) == prim;
    }
    static void rebuild(const btGImpactBoxSet& set, std::vector<int>& leaves) {
        leaves.assign(static_cast<std::size_t>(std::max(set.getPrimitiveManager()->get_primitive_count(), 0)), -1);
        for (int node = 0; node < set.getNodeCount(); ++node) {
            if (!set.isLeafNode(node)) continue;
            const int prim = set.getNodeData(node);
            if (prim >= 0 && static_cast<std::size_t>(prim) < leaves.size()) leaves[static_cast<std::size_t>(prim)] = node;
        }
    }

    std::uint64_t m_epoch = 0;
    std::unordered_map<const btGImpactBoxSet*, Entry> m_leaves;
};

}  // namespace cullide::bullet
