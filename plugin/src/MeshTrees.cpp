#include "MeshTrees.h"

#include <algorithm>
#include <cstring>

namespace cullide {
namespace {

/// The fraction of `box` inside `near`, axis by axis (an axis where `box` is flat counts 1 when it is inside).
double fractionInside(const Aabb& box, const Aabb& near) {
    double fraction = 1.0;
    for (int k = 0; k < 3; ++k) {
        const double inside = std::min(box.max[k], near.max[k]) - std::max(box.min[k], near.min[k]);
        if (!(inside >= 0.0)) return 0.0;
        const double extent = box.max[k] - box.min[k];
        if (extent > 0.0) fraction *= std::min(1.0, inside / extent);
    }
    return fraction;
}

}  // namespace

void MeshTrees::choose(FrameState& frame) {
    const std::size_t n = frame.valid.size();
    frame.whole.assign(n, 0);
    frame.tree.assign(n, nullptr);
    for (std::uint32_t o = 0; o < n; ++o) {
        if (!frame.isActiveMesh(o) || frame.meshOf(o).triangles.empty()) continue;
        if (frame.statics.entry[o] != nullptr) {
            frame.whole[o] = 1;
            continue;
        }
        Aabb near;
        for (std::uint32_t p : frame.partners[o]) near.grow(frame.valid[p].box);
        frame.whole[o] = fractionInside(frame.valid[o].box, near) >= kNearFraction ? 1 : 0;
    }
}

bool MeshTrees::needsBuild(const FrameState& frame, std::uint32_t o) {
    if (!frame.hasWholeTree(o)) return false;
    const StaticEntry* e = frame.statics.entry[o];
    return e == nullptr || !e->treeReady;
}

void MeshTrees::build(FrameState& frame, double margin, TaskPool& pool, Stats& stats) {
    struct Build {
        std::uint32_t object;
        BoxTree* tree;
    };
    std::vector<Build> builds;
    std::size_t frameTrees = 0;
    for (std::uint32_t o = 0; o < frame.whole.size(); ++o)
        frameTrees += frame.whole[o] && frame.statics.entry[o] == nullptr ? 1 : 0;
    if (m_frameTrees.size() < frameTrees) m_frameTrees.resize(frameTrees);  // before any pointer into it is taken
    frameTrees = 0;
    for (std::uint32_t o = 0; o < frame.whole.size(); ++o) {
        if (!frame.whole[o]) continue;
        StaticEntry* e = frame.statics.entry[o];
        if (e != nullptr && e->treeReady) {
            frame.tree[o] = &e->tree;
            ++stats.exactTreesKept;
            continue;
        }
        BoxTree* tree = nullptr;
        if (e != nullptr) {
            tree = &e->tree;
            e->treeReady = true;  // built below
        } else {
            tree = &m_frameTrees[frameTrees++];
        }
        builds.push_back({o, tree});
        frame.tree[o] = tree;
        ++stats.exactTreesWhole;
    }
    const double inflate = 0.5 * margin;
    BoxTree::buildMany(
        pool, builds.size(), [&](std::size_t i) { return frame.meshOf(builds[i].object).triangles.size(); },
        [&](std::size_t i, TaskPool* on) {
            const std::uint32_t o = builds[i].object;
            builds[i].tree->buildWhole(frame.meshOf(o), *frame.order[o], inflate, on);
        });
}

void MeshTrees::listPairedTriangles(const Result& result, FrameState& frame, TaskPool& pool) {
    std::vector<std::uint32_t> meshes;  // the chosen meshes, and at slot[o] each one's place among them
    std::vector<std::uint32_t> slot(frame.whole.size(), 0);
    for (std::uint32_t o = 0; o < frame.whole.size(); ++o) {
        if (!frame.whole[o]) continue;
        slot[o] = static_cast<std::uint32_t>(meshes.size());
        meshes.push_back(o);
    }
    if (m_sides.size() < meshes.size()) m_sides.resize(meshes.size());
    for (std::size_t m = 0; m < meshes.size(); ++m) m_sides[m].clear();
    for (std::uint32_t i = 0; i < result.pairs.size(); ++i) {
        const ObjectPair& pair = result.pairs[i];
        if (frame.hasWholeTree(pair.a)) m_sides[slot[pair.a]].emplace_back(i, 0);
        if (frame.hasWholeTree(pair.b)) m_sides[slot[pair.b]].emplace_back(i, 1);
    }
    pool.parallelFor(meshes.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t m = begin; m < end; ++m) {
            const std::uint32_t o = meshes[m];
            listTriangles(result, m_sides[m], frame.meshOf(o).triangles.size(), frame.surviving[o]);
        }
    });
}

void MeshTrees::listTriangles(const Result& result, const PairSides& sides, std::size_t triangleCount,
                              std::vector<std::uint32_t>& list) {
    list.clear();
    if (sides.size() == 1 && sides[0].second == 0) {  // side a of one pair: its triangles come sorted
        for (const TrianglePair& t : result.pairs[sides[0].first].triangles)
            if (list.empty() || list.back() != t.a) list.push_back(t.a);
        return;
    }
    std::size_t named = 0;
    for (const auto& [pair, side] : sides) named += result.pairs[pair].triangles.size();
    if (named * kSortedFraction < triangleCount) {  // few: sorted
        for (const auto& [pair, side] : sides)
            for (const TrianglePair& t : result.pairs[pair].triangles) list.push_back(side == 0 ? t.a : t.b);
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        return;
    }
    // Many: marked, then read back in order, eight flags at a time (no sort of a list as long as a fair part of
    // the mesh).
    thread_local std::vector<std::uint8_t> marked;
    const std::size_t words = (triangleCount + 7) / 8;
    marked.assign(words * 8, 0);
    for (const auto& [pair, side] : sides)
        for (const TrianglePair& t : result.pairs[pair].triangles) marked[side == 0 ? t.a : t.b] = 1;
    for (std::size_t w = 0; w < words; ++w) {
        std::uint64_t flags = 0;
        std::memcpy(&flags, &marked[w * 8], sizeof flags);
        if (flags == 0) continue;
        for (std::size_t t = w * 8; t < w * 8 + 8; ++t)
            if (marked[t]) list.push_back(static_cast<std::uint32_t>(t));
    }
}

}  // namespace cullide
