#include "ExactStage.h"

#include "FrameObjects.h"
#include "cullide/TriangleTest.h"

#include <algorithm>

namespace cullide {
namespace {

struct BoxRef {
    Aabb box;
    std::uint32_t triangle;
};

void sortedBoxes(const TriangleMesh& mesh, const std::vector<std::uint32_t>& triangles, double inflate, int axis,
                 std::vector<BoxRef>& out) {
    out.clear();
    out.reserve(triangles.size());
    for (std::uint32_t t : triangles) out.push_back({triangleBounds(mesh, t).inflated(inflate), t});
    std::sort(out.begin(), out.end(), [axis](const BoxRef& x, const BoxRef& y) {
        return x.box.min[axis] != y.box.min[axis] ? x.box.min[axis] < y.box.min[axis] : x.triangle < y.triangle;
    });
}

/// Every pair (one box from each list) whose boxes overlap, exactly once.
void sweep(const std::vector<BoxRef>& a, const std::vector<BoxRef>& b, int axis, std::vector<TrianglePair>& out) {
    std::size_t i = 0;
    std::size_t j = 0;
    while (i < a.size() && j < b.size()) {
        if (a[i].box.min[axis] <= b[j].box.min[axis]) {
            for (std::size_t k = j; k < b.size() && b[k].box.min[axis] <= a[i].box.max[axis]; ++k)
                if (a[i].box.overlaps(b[k].box)) out.push_back({a[i].triangle, b[k].triangle});
            ++i;
        } else {
            for (std::size_t k = i; k < a.size() && a[k].box.min[axis] <= b[j].box.max[axis]; ++k)
                if (a[k].box.overlaps(b[j].box)) out.push_back({a[k].triangle, b[j].triangle});
            ++j;
        }
    }
}

}  // namespace

void ExactStage::run(const std::vector<Object>& objects, const std::vector<ExactJob>& jobs, double margin,
                     std::vector<ExactJobResult>& results, Stats& stats) {
    results.assign(jobs.size(), ExactJobResult{});
    m_candidates.resize(jobs.size());
    // Phase 1: candidates per job (sweep and prune along the widest axis of the pair).
    m_pool.parallelFor(jobs.size(), 1, [&](std::size_t begin, std::size_t end) {
        std::vector<BoxRef> boxesA;
        std::vector<BoxRef> boxesB;
        for (std::size_t j = begin; j < end; ++j) {
            const ExactJob& job = jobs[j];
            const TriangleMesh& ma = *objects[job.a].mesh;
            const TriangleMesh& mb = *objects[job.b].mesh;
            Aabb bounds;
            for (std::uint32_t t : *job.trianglesA) bounds.grow(triangleBounds(ma, t));
            int axis = 0;
            bounds.extent().maxCoeff(&axis);
            sortedBoxes(ma, *job.trianglesA, 0.5 * margin, axis, boxesA);
            sortedBoxes(mb, *job.trianglesB, 0.5 * margin, axis, boxesB);
            m_candidates[j].clear();
            sweep(boxesA, boxesB, axis, m_candidates[j]);
            results[j].candidates = m_candidates[j].size();
        }
    });
    // Phase 2: exact tests over all candidates, flattened so that one large pair still uses every worker.
    std::vector<std::size_t> offsets(jobs.size() + 1, 0);
    for (std::size_t j = 0; j < jobs.size(); ++j) offsets[j + 1] = offsets[j] + m_candidates[j].size();
    const std::size_t total = offsets.back();
    std::vector<std::uint8_t> hit(total, 0);
    m_pool.parallelFor(total, 2048, [&](std::size_t begin, std::size_t end) {
        std::size_t j = static_cast<std::size_t>(std::upper_bound(offsets.begin(), offsets.end(), begin) -
                                                 offsets.begin()) - 1;
        for (std::size_t k = begin; k < end; ++k) {
            while (k >= offsets[j + 1]) ++j;
            const ExactJob& job = jobs[j];
            const TrianglePair& p = m_candidates[j][k - offsets[j]];
            const TriangleMesh& ma = *objects[job.a].mesh;
            const TriangleMesh& mb = *objects[job.b].mesh;
            const auto& ta = ma.triangles[p.a];
            const auto& tb = mb.triangles[p.b];
            hit[k] = trianglesWithin(ma.vertices[ta[0]], ma.vertices[ta[1]], ma.vertices[ta[2]], mb.vertices[tb[0]],
                                     mb.vertices[tb[1]], mb.vertices[tb[2]], margin);
        }
    });
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        auto& out = results[j].triangles;
        for (std::size_t k = 0; k < m_candidates[j].size(); ++k)
            if (hit[offsets[j] + k]) out.push_back(m_candidates[j][k]);
        std::sort(out.begin(), out.end());
        stats.intersectingTrianglePairs += out.size();
    }
    stats.candidateTrianglePairs += total;
    stats.exactTests += total;
}

}  // namespace cullide
