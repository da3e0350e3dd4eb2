// A flat box tree over a subset of one mesh's triangles (or all of them), built in O(n), and the simultaneous descent
// of two such trees that yields every triangle pair whose boxes overlap, exactly once.
#pragma once

#include "cullide/Result.h"
#include "cullide/TaskPool.h"
#include "cullide/Types.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace cullide {

class BoxTree {
public:
    /// Children per node. Node i of level l + 1 is the union of nodes [8i, 8i + 8) of level l; those eight are
    /// stored together as one Block, so no child pointers are stored and one node's children are tested against a
    /// box in a few SIMD instructions.
    static constexpr std::uint32_t kFanout = 8;

    /// Eight boxes, structure of arrays, in float rounded outward by a few ulps (each contains the double box it
    /// stands for).
    /// Unused slots are empty (min +inf, max -inf) and overlap nothing.
    struct alignas(32) Block {
        float lo[3][kFanout];
        float hi[3][kFanout];
    };
    struct FloatBox {
        float lo[3];
        float hi[3];
    };

    /// A pair of nodes (level, index) of two trees whose boxes overlap.
    struct NodePair {
        std::uint32_t levelA;
        std::uint32_t nodeA;
        std::uint32_t levelB;
        std::uint32_t nodeB;
    };

    /// Leaves: `boxes[t]` for each t of `triangles`, in Morton order of their centres, ties in list order (the
    /// order only affects speed, never the result). The tree keeps its own copy of the leaves' boxes.
    /// Boxes must be finite. With `pool`, each step of the build runs on its workers in chunks: the same tree
    /// for any number of workers (for large lists; a small one is cheaper built on one thread). `pool` must not be
    /// running a parallelFor already (it is not re-entrant).
    /// With `order` (a spatial order of the mesh's triangles, kept between frames: TriangleOrders; each triangle at
    /// most once), the leaves follow it instead of being sorted when `triangles` is strictly increasing, at least
    /// 1/kOrderedFraction of the order and wholly in it (a refit: no keys, no sort). Any order gives the same pairs.
    void build(const std::vector<Aabb>& boxes, const std::vector<std::uint32_t>& triangles, TaskPool* pool = nullptr,
               const std::vector<std::uint32_t>* order = nullptr);
    /// A list shorter than 1/kOrderedFraction of the mesh's order is sorted: walking the whole order would cost more.
    static constexpr std::size_t kOrderedFraction = 8;
    /// A tree of every triangle of `mesh`, leaves in `order` (a permutation of the mesh's triangles: TriangleOrders),
    /// each leaf's box its triangle's inflated by `inflate`, computed here from the vertices (no box per triangle is
    /// stored anywhere else). The mesh must be valid (indices in range, the triangles' coordinates finite). With
    /// `pool`, as build(). The same pairs as build() over every triangle's box.
    void buildWhole(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order, double inflate,
                    TaskPool* pool = nullptr);
    /// Whether the last build followed the order it was given.
    bool followedOrder() const { return m_followedOrder; }
    /// How many of `pool`'s workers a build of `leaves` leaves keeps busy (its chunks, at most the workers).
    static std::size_t buildParallelism(const TaskPool& pool, std::size_t leaves);
    /// Builds `count` trees on `pool`: build(i, p) builds tree i, on p's workers or (p null) on the calling thread.
    /// Either one tree per task, several at once, or (fewer trees than workers: one or two large meshes on a
    /// many-core machine) one after another, each on every worker, when that ends sooner by an estimate in leaves:
    /// the largest tree for one tree per task, each tree's leaves over the workers its chunks keep busy for the
    /// other way. leaves(i) is tree i's leaf count.
    static void buildMany(TaskPool& pool, std::size_t count, const std::function<std::size_t(std::size_t)>& leaves,
                          const std::function<void(std::size_t, TaskPool*)>& build);

    bool empty() const { return m_leafTriangle.empty(); }
    /// The mesh triangle of each leaf, in leaf order.
    const std::vector<std::uint32_t>& leafTriangles() const { return m_leafTriangle; }

    std::size_t size() const { return m_leafTriangle.size(); }

    /// The overlapping node pairs of `a` and `b` after descending breadth first until there are at least `target`
    /// of them or only leaf pairs are left; together they cover every overlapping leaf pair exactly once. Empty
    /// when either tree is empty or the roots do not overlap.
    static void split(const BoxTree& a, const BoxTree& b, std::size_t target, std::vector<NodePair>& out);
    /// Two trees to split, and the node pairs wanted (split()'s target).
    struct SplitJob {
        const BoxTree* a;
        const BoxTree* b;
        std::size_t target;
    };
    /// split() for each job, out[i] for jobs[i], all jobs' rounds together: each round descends every unfinished
    /// job's node pairs one step, on `pool`'s workers when there are enough of them (a single pair of large trees
    /// is split on every worker too; null: on this thread). The same node pairs as split(), in the same order.
    static void splitMany(const std::vector<SplitJob>& jobs, TaskPool* pool, std::vector<std::vector<NodePair>>& out);

    /// Every (triangle of a, triangle of b) below `start` whose double boxes overlap (closed intervals, as
    /// Aabb::overlaps), each once, appended to `out`; `stack` is working memory. Float node boxes only prune:
    /// they contain the double boxes, so no overlapping pair is lost, and each leaf pair is decided in double.
    static void leafPairs(const BoxTree& a, const BoxTree& b, const NodePair& start, std::vector<NodePair>& stack,
                          std::vector<TrianglePair>& out);

    /// True when some leaf's double box overlaps `query` (closed intervals); `stack` is working memory.
    bool anyOverlap(const Aabb& query, std::vector<NodePair>& stack) const;

private:
    /// Build steps (see build()): the leaves' triangles (m_leafTriangle) by sorting the list's Morton keys, or by
    /// taking the list's triangles in `order`; then their float boxes, then the levels above.
    void sortLeaves(const std::vector<Aabb>& boxes, const std::vector<std::uint32_t>& triangles, TaskPool* pool);
    bool canFollow(const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>* order,
                   TaskPool* pool) const;
    bool leavesInOrder(const std::vector<std::uint32_t>& triangles, const std::vector<std::uint32_t>& order,
                       TaskPool* pool);
    void fillLeaves(const std::vector<Aabb>& boxes, TaskPool* pool);
    /// Storage for n leaves (their double boxes and float blocks), before their slots are written.
    void startLeaves(std::size_t n);
    /// After the leaves' slots are written: the last block's unused slots emptied, the leaf level counted.
    void finishLeaves(std::size_t n);
    void buildLevels(TaskPool* pool);
    /// The inline members below are defined in BoxTree.cpp, the only place that calls them: they run for every node
    /// pair of a descent (as calls, they cost env3's one-thread frame about a tenth).
    inline FloatBox box(std::uint32_t level, std::uint32_t node) const;
    /// Bit i set when child i of `node` (at `level` > 0) overlaps `q`.
    inline unsigned childMask(std::uint32_t level, std::uint32_t node, const FloatBox& q) const;
    /// Expands `p` (not a leaf pair): overlapping leaf pairs go to `out`, other overlapping node pairs to `pending`.
    static inline void descend(const BoxTree& a, const BoxTree& b, const NodePair& p,
                               std::vector<NodePair>& pending, std::vector<TrianglePair>* out);
    inline bool leavesOverlap(std::uint32_t leaf, const BoxTree& other, std::uint32_t otherLeaf) const;

    std::vector<std::vector<Block>> m_levels;  ///< [l] holds the nodes of level l (0 = leaves) in blocks of eight
    std::uint32_t m_levelCount = 0;           ///< levels in use; the top one holds the root alone; more are spare
    std::vector<std::size_t> m_nodeCount;      ///< nodes per level in use
    std::vector<std::uint32_t> m_leafTriangle;  ///< mesh triangle of each leaf
    std::vector<Aabb> m_leafBox;                ///< the double box of each leaf, in leaf order
    std::vector<std::uint64_t> m_keys;           ///< build scratch: Morton code << 32 | position
    std::vector<std::uint64_t> m_keysTmp;
    std::vector<std::uint8_t> m_inList;          ///< build scratch, by triangle: 1 while in the list (then 0 again)
    std::vector<std::size_t> m_chunkFirst;       ///< build scratch: first leaf of each chunk of the order
    bool m_followedOrder = false;
    std::vector<Aabb> m_chunkBounds;             ///< build scratch: bounds of each chunk of the list
    std::vector<std::uint32_t> m_histogram;      ///< build scratch: digit counts of each chunk, then its cursors
};

}  // namespace cullide
