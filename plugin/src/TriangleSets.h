// The CPU stages over the active meshes' triangles: their boxes and groups of k in each mesh's kept spatial order
// (what the visibility levels start from), and the triangles whose boxes meet a partner's (the CPU path, and what
// is left when the levels cannot run). All run on the pool; results do not depend on the number of workers.
#pragma once

#include "FrameState.h"
#include "cullide/TaskPool.h"
#include "cullide/Stats.h"

#include <cstdint>
#include <vector>

namespace cullide {

/// Working memory of these stages, kept between frames (no allocation churn on large scenes).
struct TriangleScratch {
    struct Range {
        std::uint32_t object;
        std::uint32_t begin;
        std::uint32_t end;
    };
    std::vector<Range> ranges;
    std::vector<std::vector<std::uint32_t>> rangeKept;
    std::vector<std::uint8_t> groupKept;
    std::vector<std::vector<FrameTriangle>> taskTriangles;
    std::vector<Aabb> partnerUnion;
    std::vector<std::uint8_t> needBoxes;
    /// Per object, where its group boxes come from (buildGroups): its vertices or kept triangle boxes (kOwnVertices),
    /// or a moving mesh's own-frame group boxes, kept (kLocalKept) or computed now (kLocalComputed).
    enum GroupBoxSource : std::uint8_t { kOwnVertices, kLocalKept, kLocalComputed };
    std::vector<std::uint8_t> groupBoxSource;
};

/// Sets frame.boxesOf for every active mesh and computes the triangle boxes of new static meshes; with GPU levels
/// (frame.gpuLevels) also each active mesh's groups of `groupSize` triangles consecutive in its spatial order
/// (frame.order, which must be set for every active mesh) with their boxes, into frame.allGroups, and those whose box
/// overlaps a partner's box (all, without `prepass`) into frame.groups.
/// The other meshes' triangle boxes are computed as the stages reach their triangles: collectDirect on the CPU path;
/// with GPU levels collectTriangles, and computeSurvivorBoxes once the levels have run. A group's box comes from its
/// vertices; with `prepass`, a moving keyed mesh's (StaticLookup::moving) from its box in the mesh's own frame, kept
/// between frames.
void buildTriangleBoxesAndGroups(FrameState& frame, std::uint32_t groupSize, double margin, bool prepass,
                                 TaskPool& pool, TriangleScratch& scratch, Stats& stats);

/// The triangles of `groups` (each in the object's spatial order, FrameState::order), in group order; with
/// `prepass`, only those whose box overlaps a partner object's box (tested when the object has at most 16 partners).
/// Stores the box (inflated by `margin` / 2) of every triangle of the groups that is not kept from an earlier frame.
void collectTriangles(FrameState& frame, const std::vector<Group>& groups, bool prepass, double margin,
                      TaskPool& pool, TriangleScratch& scratch, std::vector<FrameTriangle>& triangles);

/// The CPU path (no GPU levels), in one pass on every worker: each active mesh's triangle boxes (those not kept from
/// an earlier frame) and its surviving triangles into frame.surviving — those whose box overlaps a partner's box
/// (with more than 16 partners, every triangle of a run of `groupSize` whose joint box does, as the group filter
/// would). Only the kept triangles' boxes are stored.
void collectDirect(FrameState& frame, std::uint32_t groupSize, double margin, TaskPool& pool,
                   TriangleScratch& scratch);

/// The triangles of `groups` as items (in group order, each group's in the object's spatial order) with alive[i] set,
/// added to frame.surviving; each list kept sorted.
void addSurvivingGroupTriangles(FrameState& frame, const std::vector<Group>& groups,
                                const std::vector<std::uint8_t>& alive);

/// With GPU levels, once frame.surviving is complete: the boxes (inflated by `margin` / 2) of every surviving triangle
/// of the meshes whose boxes are computed on demand (all but static meshes), for the exact stage.
void computeSurvivorBoxes(FrameState& frame, double margin, TaskPool& pool, TriangleScratch& scratch);

/// Adds `triangles` (those with alive[i] set; `alive` empty: all) to frame.surviving and keeps each list sorted.
void addSurvivingTriangles(FrameState& frame, const std::vector<FrameTriangle>& triangles,
                           const std::vector<std::uint8_t>& alive);

}  // namespace cullide
