#include "TriangleSets.h"

#include "KeptCapacity.h"
#include "PoolOrHere.h"
#include "WorldMeshes.h"

#include <algorithm>

namespace cullide {
namespace {

/// Ranges of at most `range` of count(o) elements (by default the mesh's triangles) over the objects for which take(o)
/// holds, in object and element order.
template <typename Take, typename Count>
void splitIntoRanges(const FrameState& frame, const Take& take, const Count& count, std::uint32_t range,
                     std::vector<TriangleScratch::Range>& ranges) {
    ranges.clear();
    for (std::uint32_t o = 0; o < frame.valid.size(); ++o) {
        if (!take(o)) continue;
        const auto n = static_cast<std::uint32_t>(count(o));
        for (std::uint32_t first = 0; first < n; first += range) ranges.push_back({o, first, std::min(n, first + range)});
    }
}

template <typename Take>
void splitIntoRanges(const FrameState& frame, const Take& take, std::uint32_t range,
                     std::vector<TriangleScratch::Range>& ranges) {
    splitIntoRanges(frame, take, [&](std::uint32_t o) { return frame.meshOf(o).triangles.size(); }, range, ranges);
}

/// Whether object o's triangle boxes are computed as the frame's stages reach its triangles: those of every mesh but a
/// static one (whose boxes are kept between frames, StaticEntry).
bool boxesOnDemand(const FrameState& frame, std::uint32_t o) { return frame.statics.entry[o] == nullptr; }

/// Which meshes get their triangle boxes computed now (scratch.needBoxes: new static meshes), and where each active
/// mesh's boxes live (frame.boxesOf).
void assignBoxStorage(FrameState& frame, TriangleScratch& scratch) {
    const std::size_t n = frame.valid.size();
    frame.ownBoxes.resize(n);
    frame.boxesOf.assign(n, nullptr);
    scratch.needBoxes.assign(n, 0);
    for (std::uint32_t o = 0; o < n; ++o) {
        if (!frame.isActiveMesh(o) || frame.hasWholeTree(o)) continue;  // a whole tree holds its own boxes
        const std::size_t triangles = frame.meshOf(o).triangles.size();
        StaticEntry* e = frame.statics.entry[o];
        if (e == nullptr) {  // filled on demand
            resizeKeeping(frame.ownBoxes[o], triangles);
            frame.boxesOf[o] = &frame.ownBoxes[o];
            continue;
        }
        frame.boxesOf[o] = &e->boxes;
        if (e->boxesReady) continue;
        e->boxes.resize(triangles);
        e->boxesReady = true;  // filled by the caller
        scratch.needBoxes[o] = 1;
    }
}

/// The box of the triangles order[first, first + count) of `mesh`, inflated: the union of their triangleBounds, bit
/// for bit (subtracting, or adding, `inflate` is monotone in the rounded result), without storing theirs.
Aabb groupBounds(const TriangleMesh& mesh, const std::vector<std::uint32_t>& order, std::uint32_t first,
                 std::uint32_t count, double inflate) {
    Vec3 lo = mesh.vertices[mesh.triangles[order[first]][0]], hi = lo;
    for (std::uint32_t k = first; k < first + count; ++k) {
        for (std::uint32_t v : mesh.triangles[order[k]]) {
            const Vec3& p = mesh.vertices[v];
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], p[a]);
                hi[a] = std::max(hi[a], p[a]);
            }
        }
    }
    Aabb box;
    for (int a = 0; a < 3; ++a) {
        box.min[a] = lo[a] - inflate;
        box.max[a] = hi[a] + inflate;
    }
    return box;
}

/// Makes room for a moving mesh's own-frame group boxes (StaticEntry::localGroupBoxes) where it has none for groups
/// of k in the spatial order of serial `order`; returns whether they are computed this frame.
/// They hold for that order only once computed (finishLocalGroupBoxes): a frame that ends before leaves none.
bool prepareLocalGroupBoxes(StaticEntry& e, std::size_t triangles, std::uint32_t k, std::uint64_t order) {
    const std::size_t groups = (triangles + k - 1) / k;
    if (e.groupSize == k && e.groupOrder == order && e.localGroupBoxes.size() == groups) return false;
    e.groupSize = k;
    e.groupOrder = 0;
    e.localGroupBoxes.assign(groups, Aabb{});
    return true;
}

/// After the group pass: the own-frame group boxes computed in it hold for their order.
void finishLocalGroupBoxes(const FrameState& frame, const TriangleScratch& scratch) {
    for (std::uint32_t o = 0; o < scratch.groupBoxSource.size(); ++o)
        if (scratch.groupBoxSource[o] == TriangleScratch::kLocalComputed)
            frame.movingEntry(o)->groupOrder = frame.orderSerial[o];
}

/// A moving mesh's group box: the world box of its box in the mesh's own frame (computed now where `compute`), which
/// holds every transformed vertex of the group (transformedBounds), inflated. It holds the group's triangles' boxes
/// (an exact box would cost mapping its vertices); in the Auto pipeline only the CPU's box pre-pass reads it (the
/// device builds the groups' boxes of a mapped mesh from its vertices), so it decides which groups the levels see,
/// never what they prune.
Aabb movingGroupBox(const FrameState& frame, const Group& g, std::uint32_t k, bool compute, double inflate) {
    StaticEntry& e = *frame.movingEntry(g.object);
    const Object& input = (*frame.inputs)[g.object];
    Aabb& local = e.localGroupBoxes[g.first / k];
    if (compute) local = groupBounds(*input.mesh, *frame.order[g.object], g.first, g.count, 0.0);
    return transformedBounds(*input.transform, local).inflated(inflate);
}

/// Every group of k triangles of the active meshes, with its box (from the triangle boxes of a static mesh, from its
/// box in the mesh's own frame for a moving one when `prepass` is on, from the vertices of any other); kept
/// (frame.groups) when `prepass` is off or its box overlaps a partner's. (Without `prepass`, the paper's pipeline,
/// group boxes are its group level's item boxes: exact ones, so that its sets do not depend on keys.)
void buildGroups(FrameState& frame, std::uint32_t k, double margin, bool prepass, TaskPool& pool,
                 TriangleScratch& scratch, Stats& stats) {
    std::vector<Group>& candidates = frame.allGroups;
    candidates.clear();
    scratch.groupBoxSource.assign(frame.valid.size(), TriangleScratch::kOwnVertices);
    for (std::uint32_t o = 0; o < frame.valid.size(); ++o) {
        if (!frame.isActiveMesh(o)) continue;
        const auto n = static_cast<std::uint32_t>(frame.meshOf(o).triangles.size());
        StaticEntry* e = prepass ? frame.movingEntry(o) : nullptr;
        if (e != nullptr)
            scratch.groupBoxSource[o] = prepareLocalGroupBoxes(*e, n, k, frame.orderSerial[o])
                                            ? TriangleScratch::kLocalComputed
                                            : TriangleScratch::kLocalKept;
        for (std::uint32_t first = 0; first < n; first += k) {
            const auto index = static_cast<std::uint32_t>(candidates.size());
            candidates.push_back({o, first, std::min(k, n - first), {}, index});
        }
    }
    resizeKeeping(scratch.groupKept, candidates.size());
    pool.parallelFor(candidates.size(), 256, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            Group& g = candidates[i];
            const std::vector<std::uint32_t>& order = *frame.order[g.object];
            if (const std::uint8_t source = scratch.groupBoxSource[g.object]; source != TriangleScratch::kOwnVertices) {
                g.box = movingGroupBox(frame, g, k, source == TriangleScratch::kLocalComputed, 0.5 * margin);
            } else if (boxesOnDemand(frame, g.object)) {
                g.box = groupBounds(frame.meshOf(g.object), order, g.first, g.count, 0.5 * margin);
            } else {
                const std::vector<Aabb>& boxes = *frame.boxesOf[g.object];
                for (std::uint32_t t = g.first; t < g.first + g.count; ++t) g.box.grow(boxes[order[t]]);
            }
            scratch.groupKept[i] = !prepass || frame.overlapsPartner(g.object, g.box);
        }
    });
    finishLocalGroupBoxes(frame, scratch);
    stats.prepassGroupsIn += candidates.size();
    frame.groups.clear();
    for (std::size_t i = 0; i < candidates.size(); ++i)
        if (scratch.groupKept[i]) frame.groups.push_back(candidates[i]);
    stats.prepassGroupsOut = frame.groups.size();
}

}  // namespace

void buildTriangleBoxesAndGroups(FrameState& frame, std::uint32_t groupSize, double margin, bool prepass,
                                 TaskPool& pool, TriangleScratch& scratch, Stats& stats) {
    frame.groups.clear();
    frame.allGroups.clear();
    assignBoxStorage(frame, scratch);
    splitIntoRanges(frame, [&](std::uint32_t o) { return scratch.needBoxes[o] != 0; }, 8192, scratch.ranges);
    const double inflate = 0.5 * margin;
    pool.parallelFor(scratch.ranges.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t r = begin; r < end; ++r) {
            const TriangleScratch::Range& range = scratch.ranges[r];
            const TriangleMesh& mesh = frame.meshOf(range.object);
            std::vector<Aabb>& boxes = *frame.boxesOf[range.object];
            for (std::uint32_t t = range.begin; t < range.end; ++t) boxes[t] = triangleBounds(mesh, t, inflate);
        }
    });
    if (frame.gpuLevels) buildGroups(frame, groupSize, margin, prepass, pool, scratch, stats);
}

namespace {

/// Whether the box pre-pass keeps triangle t of `object`: its box overlaps a partner object's box (tested where the
/// object has at most 16 partners; with more, every triangle is kept).
bool keptByPrepass(const FrameState& frame, std::uint32_t object, std::uint32_t t) {
    return frame.partners[object].size() > 16 || frame.overlapsPartner(object, (*frame.boxesOf[object])[t]);
}

}  // namespace

void collectTriangles(FrameState& frame, const std::vector<Group>& groups, bool prepass, double margin,
                      TaskPool& pool, TriangleScratch& scratch, std::vector<FrameTriangle>& triangles) {
    const double inflate = 0.5 * margin;
    constexpr std::size_t kGroupsPerTask = 256;
    const std::size_t tasks = (groups.size() + kGroupsPerTask - 1) / kGroupsPerTask;
    if (scratch.taskTriangles.size() < tasks) scratch.taskTriangles.resize(tasks);
    pool.parallelFor(tasks, 1, [&](std::size_t begin, std::size_t end) {
        thread_local std::vector<FrameTriangle> kept;  // per thread: neighbouring tasks' vectors share cache lines
        for (std::size_t task = begin; task < end; ++task) {
            kept.clear();
            const std::size_t last = std::min(groups.size(), (task + 1) * kGroupsPerTask);
            for (std::size_t i = task * kGroupsPerTask; i < last; ++i) {
                const Group& g = groups[i];
                const bool compute = boxesOnDemand(frame, g.object);
                std::vector<Aabb>& boxes = *frame.boxesOf[g.object];
                for (std::uint32_t k = g.first; k < g.first + g.count; ++k) {
                    const std::uint32_t t = (*frame.order[g.object])[k];
                    if (compute) boxes[t] = triangleBounds(frame.meshOf(g.object), t, inflate);
                    if (prepass && !keptByPrepass(frame, g.object, t)) continue;
                    kept.push_back({g.object, t, static_cast<std::uint32_t>(i)});
                }
            }
            assignKeeping(scratch.taskTriangles[task], kept.begin(), kept.end());
        }
    });
    triangles.clear();
    for (std::size_t task = 0; task < tasks; ++task)
        triangles.insert(triangles.end(), scratch.taskTriangles[task].begin(), scratch.taskTriangles[task].end());
}

void collectDirect(FrameState& frame, std::uint32_t groupSize, double margin, TaskPool& pool,
                   TriangleScratch& scratch) {
    const std::uint32_t k = groupSize;
    const std::size_t n = frame.valid.size();
    // Ranges of whole groups (the many-partner branch tests groups of k), enough of them for every worker.
    // Meshes with a whole tree have their survivors already (MeshTrees).
    auto take = [&](std::uint32_t o) { return frame.isActiveMesh(o) && !frame.hasWholeTree(o); };
    std::size_t triangles = 0;
    for (std::uint32_t o = 0; o < n; ++o)
        if (take(o)) triangles += frame.meshOf(o).triangles.size();
    const auto range = static_cast<std::uint32_t>(chunkFor(&pool, triangles, 1024, 8192));
    splitIntoRanges(frame, take, k * std::max<std::uint32_t>(1, range / k), scratch.ranges);
    if (scratch.rangeKept.size() < scratch.ranges.size()) scratch.rangeKept.resize(scratch.ranges.size());
    // The union of each object's partners' boxes: one test rejects the triangles far from all of them.
    scratch.partnerUnion.assign(n, Aabb{});
    for (std::uint32_t o = 0; o < n; ++o)
        for (std::uint32_t p : frame.partners[o]) scratch.partnerUnion[o].grow(frame.valid[p].box);
    const double inflate = 0.5 * margin;
    pool.parallelFor(scratch.ranges.size(), 1, [&](std::size_t begin, std::size_t end) {
        thread_local std::vector<std::uint32_t> kept;  // per thread: neighbouring ranges' vectors share lines
        for (std::size_t r = begin; r < end; ++r) {
            const TriangleScratch::Range& rg = scratch.ranges[r];
            const TriangleMesh& mesh = frame.meshOf(rg.object);
            std::vector<Aabb>& boxes = *frame.boxesOf[rg.object];
            const bool compute = boxesOnDemand(frame, rg.object);
            const Aabb& near = scratch.partnerUnion[rg.object];
            kept.clear();
            if (frame.partners[rg.object].size() <= 16) {
                for (std::uint32_t t = rg.begin; t < rg.end; ++t) {
                    // Only kept triangles' boxes are read later: the others are not stored (memory traffic).
                    const Aabb box = compute ? triangleBounds(mesh, t, inflate) : boxes[t];
                    if (!box.overlaps(near) || !frame.overlapsPartner(rg.object, box)) continue;
                    if (compute) boxes[t] = box;
                    kept.push_back(t);
                }
            } else {
                for (std::uint32_t first = rg.begin; first < rg.end; first += k) {
                    const std::uint32_t last = std::min(rg.end, first + k);
                    Aabb box;
                    for (std::uint32_t t = first; t < last; ++t) {
                        if (compute) boxes[t] = triangleBounds(mesh, t, inflate);
                        box.grow(boxes[t]);
                    }
                    if (!box.overlaps(near) || !frame.overlapsPartner(rg.object, box)) continue;
                    for (std::uint32_t t = first; t < last; ++t) kept.push_back(t);
                }
            }
            assignKeeping(scratch.rangeKept[r], kept.begin(), kept.end());
        }
    });
    for (std::size_t r = 0; r < scratch.ranges.size(); ++r) {  // ranges in object and triangle order: sorted lists
        auto& list = frame.surviving[scratch.ranges[r].object];
        list.insert(list.end(), scratch.rangeKept[r].begin(), scratch.rangeKept[r].end());
    }
}

namespace {

void sortSurviving(FrameState& frame) {
    for (auto& list : frame.surviving)
        if (!std::is_sorted(list.begin(), list.end())) std::sort(list.begin(), list.end());
}

}  // namespace

void addSurvivingTriangles(FrameState& frame, const std::vector<FrameTriangle>& triangles,
                           const std::vector<std::uint8_t>& alive) {
    for (std::size_t i = 0; i < triangles.size(); ++i)
        if (alive.empty() || alive[i]) frame.surviving[triangles[i].object].push_back(triangles[i].triangle);
    sortSurviving(frame);
}

void addSurvivingGroupTriangles(FrameState& frame, const std::vector<Group>& groups,
                                const std::vector<std::uint8_t>& alive) {
    std::size_t i = 0;
    for (const Group& g : groups) {
        const std::vector<std::uint32_t>& order = *frame.order[g.object];
        for (std::uint32_t k = g.first; k < g.first + g.count; ++k, ++i)
            if (alive[i]) frame.surviving[g.object].push_back(order[k]);
    }
    sortSurviving(frame);
}

void computeSurvivorBoxes(FrameState& frame, double margin, TaskPool& pool, TriangleScratch& scratch) {
    splitIntoRanges(
        frame, [&](std::uint32_t o) { return frame.isActiveMesh(o) && boxesOnDemand(frame, o); },
        [&](std::uint32_t o) { return frame.surviving[o].size(); }, 4096, scratch.ranges);  // ranges of the lists
    const double inflate = 0.5 * margin;
    pool.parallelFor(scratch.ranges.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t r = begin; r < end; ++r) {
            const TriangleScratch::Range& range = scratch.ranges[r];
            const TriangleMesh& mesh = frame.meshOf(range.object);
            const std::vector<std::uint32_t>& list = frame.surviving[range.object];
            std::vector<Aabb>& boxes = *frame.boxesOf[range.object];
            for (std::uint32_t k = range.begin; k < range.end; ++k)
                boxes[list[k]] = triangleBounds(mesh, list[k], inflate);
        }
    });
}

}  // namespace cullide
