// The CPU path's box trees of whole meshes. A static mesh's (Object::staticKey) is built once and kept with its
// StaticEntry; a mesh lying mostly near its partners gets one each frame, straight from its vertices in its kept
// spatial order. For those meshes it replaces both the per-triangle box pass (collectDirect) and the exact stage's
// tree over the surviving triangles, with the same candidate pairs: a triangle whose box meets no partner's object
// box meets no partner triangle's box, so the extra leaves never pair.
#pragma once

#include "FrameState.h"
#include "cullide/Result.h"
#include "cullide/Stats.h"
#include "cullide/TaskPool.h"

#include <cstdint>
#include <vector>

namespace cullide {

class MeshTrees {
public:
    /// A mesh without a kept tree gets a whole tree when at least this fraction of its box lies in the box around
    /// its partners' boxes (a cheap estimate of how many of its triangles survive the pre-pass; it affects speed
    /// only).
    static constexpr double kNearFraction = 0.125;
    /// A chosen mesh's paired triangles are sorted when its pairs name fewer than 1/kSortedFraction of its triangles,
    /// else marked in a flag per triangle and read back in order (speed only).
    static constexpr std::size_t kSortedFraction = 32;

    /// Sets frame.whole (one entry per object) for the CPU path: every active static mesh (one with a StaticEntry)
    /// and every active mesh with at least kNearFraction of its box near its partners'. Clears frame.tree.
    static void choose(FrameState& frame);

    /// Whether o's tree is to be built this frame (it needs frame.order[o]): chosen, and not kept from earlier.
    static bool needsBuild(const FrameState& frame, std::uint32_t o);

    /// For every chosen mesh, its tree (kept, or built now from frame.order[o]) into frame.tree[o]. Counts the trees
    /// in stats (exactTreesWhole, exactTreesKept).
    void build(FrameState& frame, double margin, TaskPool& pool, Stats& stats);

    /// After the exact stage: each chosen mesh's surviving triangles (frame.surviving[o], the triangle-level PCS it
    /// reports) are the triangles its pairs in `result` name, sorted. No pre-pass ran over its triangles: the tree's
    /// descent is the pre-pass, and this is the smallest list that holds every triangle of its pairs.
    /// The meshes are listed on `pool`'s workers, one mesh per task.
    void listPairedTriangles(const Result& result, FrameState& frame, TaskPool& pool);

    /// One mesh's side of its pairs: (index into result.pairs, 0 for side a or 1 for side b).
    using PairSides = std::vector<std::pair<std::uint32_t, std::uint8_t>>;
    /// The triangles (of a mesh of `triangleCount`) that its pairs' sides name, sorted and without repeats, into
    /// `list`: sorted, marked (see kSortedFraction) or, for side a of a single pair, read off its sorted pairs.
    static void listTriangles(const Result& result, const PairSides& sides, std::size_t triangleCount,
                              std::vector<std::uint32_t>& list);

private:
    std::vector<BoxTree> m_frameTrees;  ///< this frame's trees of meshes without a kept one (memory reused)
    std::vector<PairSides> m_sides;     ///< per chosen mesh of this frame, its pairs' sides (memory reused)
};

}  // namespace cullide
