#include "MeshTrees.h"

#include <algorithm>

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

void MeshTrees::listPairedTriangles(const Result& result, FrameState& frame) {
    for (const ObjectPair& pair : result.pairs) {
        if (frame.hasWholeTree(pair.a))
            for (const TrianglePair& t : pair.triangles) frame.surviving[pair.a].push_back(t.a);
        if (frame.hasWholeTree(pair.b))
            for (const TrianglePair& t : pair.triangles) frame.surviving[pair.b].push_back(t.b);
    }
    for (std::uint32_t o = 0; o < frame.whole.size(); ++o) {
        if (!frame.whole[o]) continue;
        std::vector<std::uint32_t>& list = frame.surviving[o];
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
    }
}

}  // namespace cullide
