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

/// Thrown at the start of a level once the frame's levelsDeadline has passed: the device holds nothing half done, and
/// the caller finishes the frame on the CPU path.
struct LevelsAbandoned {};

/// Runs the levels over every cluster of frame.active (clustersOf): each cluster goes to the device relative to its
/// own centre and each level's views are fitted to it, so objects far from each other cost what near ones cost.
/// Expects buildTriangleBoxesAndGroups to have run with frame.gpuLevels set. Throws BackendError (from the backend)
/// or LevelsAbandoned (past frame.levelsDeadline) with frame.surviving partly filled: the caller starts over without
/// the levels.
class LevelPipelines {
public:
    void run(FrameState& frame, const Settings& settings, PruningBackend& backend, TaskPool& pool,
             TriangleScratch& scratch, Stats& stats);

private:
    // Kept between frames: the device's copy of the geometry (and its resident region) and allocations.
    ClusterGeometry m_geometry;
    LevelItems m_items;
    std::vector<std::uint8_t> m_survivors;
    std::vector<std::uint32_t> m_ownerId;
    std::vector<FrameTriangle> m_triangles;
};

}  // namespace cullide
