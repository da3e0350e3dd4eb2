// The visibility levels of one frame (GPU levels on): cluster by cluster, the Auto pipeline (group boxes, then
// triangles) or the paper's (objects as boxes, objects as triangles, groups, triangles), each level a pruneLevel on
// the backend; the triangles that survive go to FrameState::surviving.
#pragma once

#include "ClusterGeometry.h"
#include "FrameState.h"
#include "PruningBackend.h"
#include "cullide/TaskPool.h"
#include "TriangleSets.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <vector>

namespace cullide {

/// Largest cluster extent whose coordinates, relative to its centre, the visibility levels take as floats (with room
/// for the views' arithmetic below FLT_MAX). Wider clusters are not rasterised: every triangle that the box
/// pre-pass keeps goes to the exact stage.
constexpr double kRasterisableExtent = 1e30;

/// A triangle range of a level described by its objects: its items are the triangles of `object` from localFirst on
/// in its spatial order (FrameState::order).
struct TriangleRange {
    std::uint32_t itemBegin;
    std::uint32_t count;
    std::uint32_t object;
    std::uint32_t localFirst;
};

/// Thrown at the start of a level once the frame's levelsDeadline has passed: the device holds nothing half done, and
/// the caller finishes the frame on the CPU path.
struct LevelsAbandoned {};

/// Runs the levels over every cluster of frame.active (clustersOf): each cluster goes to the device relative to its
/// own centre and each level's views are fitted to it, so objects far from each other cost what near ones cost.
/// The Auto pipeline's triangle levels are read back together at the end of the frame: one wait per frame. Expects
/// buildTriangleBoxesAndGroups to have run with frame.gpuLevels set. Throws BackendError (from the backend),
/// LevelsAbandoned (past frame.levelsDeadline) or RunAbandoned (past frame.runDeadline) with frame.surviving partly
/// filled: the caller starts over without the levels.
class LevelPipelines {
public:
    void run(FrameState& frame, const Settings& settings, PruningBackend& backend, TaskPool& pool,
             TriangleScratch& scratch, Stats& stats);

private:
    /// A cluster whose triangle level is read back with the frame's others: its levels are
    /// stats.levels[firstLevel .. endLevel), its places from firstPlace on.
    struct DeferredCluster {
        Cluster cluster;
        std::size_t firstPlace = 0;
        std::size_t firstLevel = 0;
        std::size_t endLevel = 0;
        std::vector<TriangleRange> exactRanges;  ///< where the device exact stage ran after its triangle level
    };

    /// The device exact stage's pairs of a deferred cluster (item pairs, DeferredLevel::exactPairs) into
    /// frame.devicePairs, and its objects marked (FrameState::exactOnDevice).
    static void addDevicePairs(FrameState& frame, const DeferredCluster& d, const std::vector<std::uint32_t>& words,
                               Stats& stats);

    /// The levels of one cluster (the Auto or the paper pipeline; a level run ahead that stopped early runs again
    /// with its cluster, waited for). `defer`: the Auto triangle level's read-back may wait for collectDeferred;
    /// returns true where it does.
    bool runCluster(FrameState& frame, const Cluster& cluster, const Settings& settings, PruningBackend& backend,
                    TaskPool& pool, TriangleScratch& scratch, Stats& stats, std::size_t& place, bool defer);

    /// One read-back for every deferred cluster (PruningBackend::collect, bounded by the frame's deadlines), then
    /// each one's surviving triangles; a cluster whose chain stopped early on the device runs again, waited for.
    void collectDeferred(FrameState& frame, const Settings& settings, PruningBackend& backend, TaskPool& pool,
                         TriangleScratch& scratch, Stats& stats);

    // Kept between frames: the device's copy of the geometry (and its resident region) and allocations.
    ClusterGeometry m_geometry;
    LevelItems m_items;
    std::vector<std::uint8_t> m_survivors;
    std::vector<std::uint32_t> m_ownerId;
    std::vector<FrameTriangle> m_triangles;
    std::vector<TriangleRange> m_triangleRanges;  ///< of the last triangle level described by its objects
    std::vector<DeferredCluster> m_deferred;
    std::vector<DeferredLevel> m_results;
};

}  // namespace cullide
