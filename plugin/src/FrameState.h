// What the stages of one culling frame share (GpuCuller.cpp): the objects after validation and the box pre-pass,
// the triangle boxes and orders built for them, and the triangles that survive. Each stage takes it explicitly and
// says what it reads and writes; the culler keeps one between frames only to reuse its allocations.
#pragma once

#include "Deadline.h"
#include "FrameObjects.h"
#include "MeshCache.h"
#include "cullide/Object.h"

#include <cstdint>
#include <utility>
#include <vector>

namespace cullide {

/// k spatially consecutive triangles of one mesh (Settings::groupSize).
struct Group {
    std::uint32_t object;
    std::uint32_t first;  ///< into the object's spatial triangle order (FrameState::order)
    std::uint32_t count;
    Aabb box;  ///< world, inflated by margin / 2
    std::uint32_t index = 0;  ///< its place in FrameState::allGroups
};

/// A triangle pair the device exact stage found (Settings::deviceExact): objects a < b and their triangles, and
/// whether the device's filter certified that they intersect (otherwise the CPU's exact predicate decides).
struct DevicePair {
    std::uint32_t a;
    std::uint32_t b;
    std::uint32_t triangleA;
    std::uint32_t triangleB;
    bool certified;
    bool operator<(const DevicePair& o) const {
        return a != o.a ? a < o.a : b != o.b ? b < o.b : triangleA != o.triangleA ? triangleA < o.triangleA
                                                                                   : triangleB < o.triangleB;
    }
};

/// One triangle of one object.
struct FrameTriangle {
    std::uint32_t object;
    std::uint32_t triangle;
    std::uint32_t group = 0;  ///< collectTriangles: the index of its group in the groups it was given
};

struct FrameState {
    /// The frame's objects, with world-space meshes for the active objects that came with a transform.
    const std::vector<Object>* objects = nullptr;
    /// The frame's objects as given: a mesh that came with a transform in its own frame (ClusterGeometry has such a
    /// mesh mapped on the device).
    const std::vector<Object>* inputs = nullptr;
    std::vector<ValidatedObject> valid;
    StaticLookup statics;
    /// Object pairs whose boxes overlap (sorted, a < b) and, per object, the other object of each.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    std::vector<std::vector<std::uint32_t>> partners;
    /// Per object: 1 when its box meets another's (only those can collide; the others are not looked at again).
    std::vector<std::uint8_t> active;
    bool gpuLevels = false;  ///< whether the visibility levels run this frame
    /// A GPU trial frame's budget (AutoLevels::trialBudgetMs): the levels stop at a level's start past it
    /// (LevelPipelines throws LevelsAbandoned) and the frame is finished on the CPU path.
    Deadline levelsDeadline;
    /// The run's budget (Culler::run with a budget): a stage that finds it spent throws RunAbandoned.
    Deadline runDeadline;

    /// Per object: all its mesh's triangles in a spatial order kept between frames (TriangleOrders), or null. Set
    /// for every active mesh when GPU levels run (their groups follow it); on the CPU path for the meshes whose
    /// surviving triangles are a large part of them (their box trees follow it).
    std::vector<const std::vector<std::uint32_t>*> order;
    std::vector<std::uint64_t> orderSerial;  ///< per object: which computation its order is (TriangleOrders)
    /// Per active non-static mesh: storage of its triangle boxes (static ones are in their StaticEntry).
    std::vector<std::vector<Aabb>> ownBoxes;
    /// Per active mesh: triangle boxes (inflated by margin / 2), of every triangle (static meshes) or only of those
    /// the stages have reached (TriangleSets.h): on the CPU path its surviving ones (none for the meshes with a whole
    /// tree); with GPU levels those collected for a level and every surviving one (computeSurvivorBoxes). Every
    /// surviving triangle's is there.
    std::vector<std::vector<Aabb>*> boxesOf;
    /// Per object, on the CPU path: 1 when its mesh has a box tree of all its triangles (MeshTrees: a static mesh, or
    /// one lying mostly near its partners) in place of per-triangle boxes (boxesOf) and a tree of its survivors.
    std::vector<std::uint8_t> whole;
    /// Per object: that tree, once built (null for every other object).
    std::vector<const BoxTree*> tree;
    /// Every group of k triangles of every active mesh, with its box, in object order (GPU levels only): the device
    /// holds all of their boxes, so that a mesh at rest keeps its own whichever groups the pre-pass keeps.
    std::vector<Group> allGroups;
    /// Those of allGroups the CPU's box pre-pass keeps (GPU levels only): which clusters are worth the levels
    /// (Settings::exactThreshold), and what the CPU path filters where the levels do not run.
    std::vector<Group> groups;
    /// Per object: its triangles that may touch another object's, sorted (what the exact stage tests).
    std::vector<std::vector<std::uint32_t>> surviving;
    /// GPU levels: per object, 1 where the device exact stage found the candidates of its mesh pairs (its cluster's
    /// stage ran and fit): they are devicePairs', and the exact stage tests only those the device left undecided.
    std::vector<std::uint8_t> exactOnDevice;
    std::vector<DevicePair> devicePairs;

    const TriangleMesh& meshOf(std::uint32_t o) const { return *(*objects)[o].mesh; }
    bool isMesh(std::uint32_t o) const { return valid[o].isMesh; }
    bool isActiveMesh(std::uint32_t o) const { return active[o] && valid[o].isMesh; }
    /// A keyed mesh whose transform changed since its last frame (StaticLookup::moving), or null.
    StaticEntry* movingEntry(std::uint32_t o) const { return statics.moving.empty() ? nullptr : statics.moving[o]; }
    bool hasWholeTree(std::uint32_t o) const { return !whole.empty() && whole[o] != 0; }
    bool pairsOnDevice(std::uint32_t o) const { return gpuLevels && !exactOnDevice.empty() && exactOnDevice[o] != 0; }
    bool overlapsPartner(std::uint32_t o, const Aabb& box) const {
        for (std::uint32_t p : partners[o])
            if (box.overlaps(valid[p].box)) return true;
        return false;
    }
};

/// The objects of one cluster (clustersOf) and the frame's groups that belong to them: what one run of the levels
/// sees.
struct Cluster {
    std::vector<std::uint32_t> objects;  ///< sorted
    std::vector<Group> groups;  ///< those the box pre-pass keeps (FrameState::groups)
    /// The groups the `Auto` levels' items cover (FrameState::allGroups), in object order: per mesh, every group from
    /// the first to the last the CPU's box pre-pass keeps — a run of its spatial order, within which the device's
    /// pre-pass decides. The groups before and after it meet no partner's box, so a large mesh far from most of its
    /// partners costs the levels its run near them, not all of its triangles.
    std::vector<Group> levelGroups;
};

}  // namespace cullide
