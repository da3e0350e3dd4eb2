#include "ExactStage.h"

#include "FrameObjects.h"
#include "cullide/TriangleTest.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

namespace cullide {
namespace {

struct BoxRef {
    Aabb box;
    std::uint32_t triangle;
};

/// One object's surviving triangles' boxes (inflated), sorted by min x, computed once per frame for all its pairs.
struct ObjectBoxes {
    std::vector<BoxRef> sorted;
    std::vector<double> prefixMaxX;  ///< max of box.max.x over sorted[0..i]: monotone, so searchable exactly
    Aabb bounds;

    void build(const TriangleMesh& mesh, const std::vector<std::uint32_t>& triangles, double inflate) {
        sorted.clear();
        sorted.reserve(triangles.size());
        bounds = Aabb{};
        for (std::uint32_t t : triangles) {
            const Aabb box = triangleBounds(mesh, t).inflated(inflate);
            sorted.push_back({box, t});
            bounds.grow(box);
        }
        std::sort(sorted.begin(), sorted.end(), [](const BoxRef& x, const BoxRef& y) {
            return x.box.min.x() != y.box.min.x() ? x.box.min.x() < y.box.min.x() : x.triangle < y.triangle;
        });
        prefixMaxX.resize(sorted.size());
        double running = -std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < sorted.size(); ++i) prefixMaxX[i] = running = std::max(running, sorted[i].box.max.x());
    }

    /// The boxes overlapping `region`: every box before the first prefix maximum reaching region.min.x ends left of
    /// the region, every box after the last min.x <= region.max.x starts right of it. No arithmetic, no rounding.
    void inRegion(const Aabb& region, std::vector<BoxRef>& out) const {
        out.clear();
        const auto first = std::lower_bound(prefixMaxX.begin(), prefixMaxX.end(), region.min.x()) - prefixMaxX.begin();
        for (auto i = static_cast<std::size_t>(first); i < sorted.size() && sorted[i].box.min.x() <= region.max.x(); ++i)
            if (sorted[i].box.overlaps(region)) out.push_back(sorted[i]);
    }
};

/// Every pair (one box from each list) whose boxes overlap, exactly once: a uniform grid over the region where
/// both sets overlap. Each pair is reported from the grid cell holding the minimum corner of the two boxes'
/// intersection, so no pair is reported twice. Boxes spanning many cells are tested directly.
class GridCandidates {
public:
    /// Buckets `b` (kept by reference until the last query) for queries with boxes from `a`.
    void build(const std::vector<BoxRef>& a, const std::vector<BoxRef>& b, const Aabb& region) {
        m_b = &b;
        m_entries.clear();
        m_largeB.clear();
        m_brute = a.size() * b.size() <= 4096;
        if (m_brute || a.empty() || b.empty()) return;
        double mean = 0.0;
        for (const BoxRef& x : a) mean += x.box.extent().maxCoeff();
        for (const BoxRef& y : b) mean += y.box.extent().maxCoeff();
        mean /= static_cast<double>(a.size() + b.size());
        const Vec3 extent = region.extent();
        m_cell = std::max({1.5 * mean, extent.maxCoeff() / 128.0, 1e-300});
        m_origin = region.min;
        for (int k = 0; k < 3; ++k)
            m_dims[k] = static_cast<std::int64_t>(std::min(128.0, std::max(1.0, std::ceil(extent[k] / m_cell))));
        // Bucket b by cell; large boxes aside.
        for (std::uint32_t j = 0; j < b.size(); ++j) {
            const auto [lo, hi] = cellRange(b[j].box);
            if (cellCount(lo, hi) > kMaxCells) {
                m_largeB.push_back(j);
                continue;
            }
            for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
                for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
                    for (std::int64_t z = lo[2]; z <= hi[2]; ++z) m_entries.push_back({key(x, y, z), j});
        }
        std::sort(m_entries.begin(), m_entries.end());
    }

    /// Candidates of the boxes a[begin, end) against the bucketed b, in a's order.
    void query(const std::vector<BoxRef>& a, std::size_t begin, std::size_t end, std::vector<TrianglePair>& out) const {
        const std::vector<BoxRef>& b = *m_b;
        if (m_brute) {
            for (std::size_t i = begin; i < end; ++i)
                for (const BoxRef& y : b)
                    if (a[i].box.overlaps(y.box)) out.push_back({a[i].triangle, y.triangle});
            return;
        }
        for (std::size_t i = begin; i < end; ++i) {
            const BoxRef& x = a[i];
            for (std::uint32_t j : m_largeB)
                if (x.box.overlaps(b[j].box)) out.push_back({x.triangle, b[j].triangle});
            const auto [lo, hi] = cellRange(x.box);
            if (cellCount(lo, hi) > kMaxCells) {  // large a: against every bucketed b, once each
                for (std::uint32_t j = 0; j < b.size(); ++j)
                    if (!isLarge(b[j].box) && x.box.overlaps(b[j].box)) out.push_back({x.triangle, b[j].triangle});
                continue;
            }
            for (std::int64_t cx = lo[0]; cx <= hi[0]; ++cx)
                for (std::int64_t cy = lo[1]; cy <= hi[1]; ++cy)
                    for (std::int64_t cz = lo[2]; cz <= hi[2]; ++cz) {
                        const std::uint64_t k = key(cx, cy, cz);
                        auto it = std::lower_bound(m_entries.begin(), m_entries.end(), std::make_pair(k, 0u));
                        for (; it != m_entries.end() && it->first == k; ++it) {
                            const BoxRef& y = b[it->second];
                            if (!x.box.overlaps(y.box)) continue;
                            const Vec3 corner = x.box.min.cwiseMax(y.box.min);
                            if (cellOf(corner[0], 0) == cx && cellOf(corner[1], 1) == cy && cellOf(corner[2], 2) == cz)
                                out.push_back({x.triangle, y.triangle});
                        }
                    }
        }
    }

private:
    static constexpr std::int64_t kMaxCells = 64;
    using Cell = std::array<std::int64_t, 3>;

    std::int64_t cellOf(double v, int axis) const {
        const double c = std::floor((v - m_origin[axis]) / m_cell);
        return std::clamp<std::int64_t>(static_cast<std::int64_t>(std::clamp(c, -1.0, 1e9)), 0, m_dims[axis] - 1);
    }
    std::pair<Cell, Cell> cellRange(const Aabb& box) const {
        Cell lo{}, hi{};
        for (int k = 0; k < 3; ++k) {
            lo[k] = cellOf(box.min[k], k);
            hi[k] = cellOf(box.max[k], k);
        }
        return {lo, hi};
    }
    static std::int64_t cellCount(const Cell& lo, const Cell& hi) {
        return (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    }
    bool isLarge(const Aabb& box) const {
        const auto [lo, hi] = cellRange(box);
        return cellCount(lo, hi) > kMaxCells;
    }
    std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) const {
        return static_cast<std::uint64_t>((x * m_dims[1] + y) * m_dims[2] + z);
    }

    double m_cell = 1.0;
    Vec3 m_origin = Vec3::Zero();
    std::array<std::int64_t, 3> m_dims{1, 1, 1};
    std::vector<std::pair<std::uint64_t, std::uint32_t>> m_entries;
    std::vector<std::uint32_t> m_largeB;
    const std::vector<BoxRef>* m_b = nullptr;
    bool m_brute = true;
};

struct JobGrid {
    std::vector<BoxRef> a;
    std::vector<BoxRef> b;
    GridCandidates grid;
};

}  // namespace

struct ExactStage::Scratch {
    std::vector<JobGrid> grids;
    std::vector<ObjectBoxes> boxes;
    std::vector<std::vector<TrianglePair>> taskOut;
};

ExactStage::ExactStage(unsigned threads) : m_pool(threads), m_scratch(std::make_unique<Scratch>()) {}
ExactStage::~ExactStage() = default;

void ExactStage::run(const std::vector<Object>& objects, const std::vector<ExactJob>& jobs, double margin, bool exact,
                     std::vector<ExactJobResult>& results, Stats& stats) {
    results.assign(jobs.size(), ExactJobResult{});
    m_candidates.resize(jobs.size());
    // Phase 1: per job, the region where the two objects' surviving triangles overlap, their boxes in it, and a
    // grid over the second object's boxes; then queries of the first object's boxes, in chunks on every worker.
    std::vector<JobGrid>& grids = m_scratch->grids;
    if (grids.size() < jobs.size()) grids.resize(jobs.size());
    const double inflate = 0.5 * margin;
    // Each object's surviving triangle boxes once, however many pairs it is in (a landscape under many bodies).
    std::vector<const std::vector<std::uint32_t>*> lists;
    std::vector<std::uint32_t> listObject;
    std::vector<std::size_t> jobListA(jobs.size()), jobListB(jobs.size());
    std::unordered_map<const std::vector<std::uint32_t>*, std::size_t> known;
    auto listIndex = [&](std::uint32_t object, const std::vector<std::uint32_t>* list) {
        const auto [it, added] = known.emplace(list, lists.size());
        if (added) {
            lists.push_back(list);
            listObject.push_back(object);
        }
        return it->second;
    };
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        jobListA[j] = listIndex(jobs[j].a, jobs[j].trianglesA);
        jobListB[j] = listIndex(jobs[j].b, jobs[j].trianglesB);
    }
    std::vector<ObjectBoxes>& boxes = m_scratch->boxes;
    if (boxes.size() < lists.size()) boxes.resize(lists.size());
    m_pool.parallelFor(lists.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) boxes[i].build(*objects[listObject[i]].mesh, *lists[i], inflate);
    });
    m_pool.parallelFor(jobs.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t j = begin; j < end; ++j) {
            const ObjectBoxes& a = boxes[jobListA[j]];
            const ObjectBoxes& b = boxes[jobListB[j]];
            JobGrid& g = grids[j];
            g.a.clear();  // reused from an earlier frame: nothing of it may survive a skipped job
            g.b.clear();
            if (!a.bounds.overlaps(b.bounds)) continue;
            const Aabb region{a.bounds.min.cwiseMax(b.bounds.min), a.bounds.max.cwiseMin(b.bounds.max)};
            a.inRegion(region, g.a);
            b.inRegion(region, g.b);
            g.grid.build(g.a, g.b, region);
        }
    });
    constexpr std::size_t kChunk = 1024;
    std::vector<std::pair<std::size_t, std::size_t>> tasks;  // (job, first box of a)
    for (std::size_t j = 0; j < jobs.size(); ++j)
        for (std::size_t i = 0; i < grids[j].a.size(); i += kChunk) tasks.emplace_back(j, i);
    std::vector<std::vector<TrianglePair>>& taskOut = m_scratch->taskOut;
    if (taskOut.size() < tasks.size()) taskOut.resize(tasks.size());
    m_pool.parallelFor(tasks.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
            const JobGrid& g = grids[tasks[t].first];
            const std::size_t first = tasks[t].second;
            taskOut[t].clear();
            g.grid.query(g.a, first, std::min(g.a.size(), first + kChunk), taskOut[t]);
        }
    });
    for (std::size_t j = 0; j < jobs.size(); ++j) m_candidates[j].clear();
    for (std::size_t t = 0; t < tasks.size(); ++t) {
        auto& c = m_candidates[tasks[t].first];
        c.insert(c.end(), taskOut[t].begin(), taskOut[t].end());
    }
    for (std::size_t j = 0; j < jobs.size(); ++j) results[j].candidates = m_candidates[j].size();
    // Phase 2: exact tests over all candidates, flattened so that one large pair still uses every worker.
    std::vector<std::size_t> offsets(jobs.size() + 1, 0);
    for (std::size_t j = 0; j < jobs.size(); ++j) offsets[j + 1] = offsets[j] + m_candidates[j].size();
    const std::size_t total = offsets.back();
    std::vector<std::uint8_t> hit(total, exact ? 0 : 1);
    if (exact) m_pool.parallelFor(total, 2048, [&](std::size_t begin, std::size_t end) {
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
        if (exact) stats.intersectingTrianglePairs += out.size();
    }
    stats.candidateTrianglePairs += total;
    if (exact) stats.exactTests += total;
}

}  // namespace cullide
