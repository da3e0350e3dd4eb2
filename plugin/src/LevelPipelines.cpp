#include "LevelPipelines.h"

#include "DeviceExact.h"
#include "KeptCapacity.h"
#include "VisibilityLevel.h"
#include "bindings.h"
#include "cullide/Timer.h"
#include "Deadline.h"

#include <algorithm>

namespace cullide {
namespace {

constexpr std::uint32_t kNoOwner = 0xFFFFFFFFu;

/// The levels of one cluster: what they read, what they write, and the buffers they reuse.
struct LevelRun {
    FrameState& frame;
    const Cluster& cluster;
    const Settings& settings;
    PruningBackend& backend;
    TaskPool& pool;
    TriangleScratch& scratch;
    Stats& stats;
    ClusterGeometry& geometry;
    LevelItems& items;
    std::vector<std::uint8_t>& survivors;  ///< of the last level, per item
    std::vector<std::uint32_t>& ownerId;   ///< per object: its compact owner id in the level being built
    std::vector<FrameTriangle>& triangles;
    std::size_t& place;  ///< the next level's place in the frame (LevelStart::place)
    std::vector<TriangleRange>& triangleRanges;  ///< the mesh ranges of the last triangle level described by objects
    std::uint32_t ownerCount = 0;
    bool uploaded = false;  ///< the cluster's geometry is on the device (sent when its first level runs)
};

/// Starts building a level's items. The cluster's geometry goes to the device only when a level actually runs.
/// `keepOwners`: the owner ids of the last level go on (a level that inherits its survivors).
void beginLevel(LevelRun& run, bool keepOwners = false) {
    if (!run.uploaded) {
        Timer upload;
        run.geometry.upload(run.frame, run.cluster, run.settings.margin, run.backend, run.pool, run.stats);
        run.stats.uploadMs += upload.ms();
        run.uploaded = true;
    }
    if (!keepOwners) {
        run.ownerId.assign(run.frame.valid.size(), kNoOwner);
        run.ownerCount = 0;
    }
    run.items.clear();
}

/// Compact owner ids for the objects present in a level.
std::uint32_t ownerOf(LevelRun& run, std::uint32_t object) {
    std::uint32_t& id = run.ownerId[object];
    if (id == kNoOwner) id = run.ownerCount++;
    return id;
}

void addBoxItem(LevelRun& run, std::uint32_t object, std::uint32_t box, const Aabb& worldBox) {
    run.items.owner.push_back(ownerOf(run, object));
    run.items.prims.push_back(box | CULLIDE_PRIM_BOX_BIT);
    run.items.primBegin.push_back(static_cast<std::uint32_t>(run.items.prims.size()));
    run.items.bounds.push_back(run.geometry.relative(worldBox));
}

void addObjectBoxItem(LevelRun& run, std::uint32_t object) {
    addBoxItem(run, object, run.geometry.objectBox(object), run.frame.valid[object].box);
}

void addTriangleItem(LevelRun& run, std::uint32_t object, const std::uint32_t* triangles, std::uint32_t count,
                     const Aabb& worldBox) {
    run.items.owner.push_back(ownerOf(run, object));
    const std::uint32_t base = run.geometry.baseTriangle(object);
    for (std::uint32_t i = 0; i < count; ++i) run.items.prims.push_back(base + triangles[i]);
    run.items.primBegin.push_back(static_cast<std::uint32_t>(run.items.prims.size()));
    run.items.bounds.push_back(run.geometry.relative(worldBox));
}

/// One item per triangle, as addTriangleItem would add them one by one (the same owner ids, in the same order),
/// filled on the workers: a triangle level has tens of thousands.
void addTriangleItems(LevelRun& run, const std::vector<FrameTriangle>& triangles) {
    for (const FrameTriangle& t : triangles) ownerOf(run, t.object);  // compact ids in order of first appearance
    LevelItems& items = run.items;
    const std::size_t first = items.size();
    const std::size_t n = triangles.size();
    resizeKeeping(items.owner, first + n);
    resizeKeeping(items.prims, items.prims.size() + n);
    resizeKeeping(items.primBegin, first + n + 1);
    resizeKeeping(items.bounds, first + n);
    const std::uint32_t firstPrim = items.primBegin[first];
    run.pool.parallelFor(n, 4096, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const FrameTriangle& t = triangles[k];
            items.owner[first + k] = run.ownerId[t.object];
            items.prims[firstPrim + k] = run.geometry.baseTriangle(t.object) + t.triangle;
            items.primBegin[first + k + 1] = firstPrim + static_cast<std::uint32_t>(k + 1);
            items.bounds[first + k] = run.geometry.relative((*run.frame.boxesOf[t.object])[t.triangle]);
        }
    });
}

/// Adds the stats of a level about to run.
LevelStats& addLevel(LevelRun& run, const char* name) {
    if (run.frame.runDeadline.expired()) throw RunAbandoned{};
    if (run.frame.levelsDeadline.expired()) throw LevelsAbandoned{};
    run.stats.levels.push_back(LevelStats{});
    run.stats.levels.back().name = name;
    return run.stats.levels.back();
}

/// Runs the level built since beginLevel; run.survivors says which items survive.
void prune(LevelRun& run, const char* name) {
    LevelStats& level = addLevel(run, name);
    pruneLevel(run.backend, run.items, run.settings, run.geometry.coordinateBound(), run.place++, run.survivors, level,
               run.stats);
}

/// Runs the level built since beginLevel with its survivors left on the backend for the next level's items to inherit;
/// false where it did not reach the backend (run.survivors then says which items survive).
bool pruneAhead(LevelRun& run, const char* name) {
    addLevel(run, name);
    return pruneLevelAhead(run.backend, run.items, run.settings, run.geometry.coordinateBound(), run.place++,
                           run.survivors, run.stats.levels.size() - 1, run.stats);
}

/// Runs the level built since beginLevel with its read-back deferred to the end of the frame; false where it did not
/// reach the backend (run.survivors then says which items survive).
bool pruneDeferred(LevelRun& run, const char* name) {
    addLevel(run, name);
    return pruneLevelDeferred(run.backend, run.items, run.settings, run.geometry.coordinateBound(), run.place++,
                              run.survivors, run.stats.levels.size() - 1, run.stats);
}

std::vector<std::uint32_t> clusterProxies(const LevelRun& run) {
    std::vector<std::uint32_t> proxies;
    for (std::uint32_t o : run.cluster.objects)
        if (!run.frame.isMesh(o)) proxies.push_back(o);
    return proxies;
}

/// Keeps the entries of `list` whose item survived; its items start at item `first` of the level.
template <typename T>
void keepSurvivors(const std::vector<std::uint8_t>& survivors, std::size_t first, std::vector<T>& list) {
    std::vector<T> kept;
    for (std::size_t i = 0; i < list.size(); ++i)
        if (survivors[first + i]) kept.push_back(list[i]);
    list.swap(kept);
}

/// Partners beyond which the device's box pre-pass keeps every item of an object without testing it: a group is
/// tested against up to this many (a loop per invocation; llvmpipe ends loops silently after 65,535 iterations), a
/// triangle against up to 16, as the CPU's pre-pass does (TriangleSets.cpp).
constexpr std::size_t kMaxGroupPartners = 4096;
constexpr std::size_t kMaxTrianglePartners = 16;

/// Adds a range of `count` items of `object` (LevelItems::objectRanges) with its partners' object boxes; `kind`
/// CULLIDE_RANGE_*, and CULLIDE_RANGE_KEEP added where it has more than `maxPartners`.
void addRange(LevelRun& run, std::uint32_t object, std::uint32_t count, std::uint32_t first, std::uint32_t parent,
              std::uint32_t kind, std::size_t maxPartners) {
    LevelItems& items = run.items;
    ObjectRange r;
    r.itemBegin = static_cast<std::uint32_t>(items.objectItems);
    r.count = count;
    r.first = first;
    r.parent = parent;
    r.owner = ownerOf(run, object);
    r.kind = kind;
    r.partnerBegin = r.partnerEnd = static_cast<std::uint32_t>(items.partnerBoxes.size());
    const std::vector<std::uint32_t>& partners = run.frame.partners[object];
    if (partners.size() > maxPartners) {
        r.kind |= CULLIDE_RANGE_KEEP;
    } else if ((kind & CULLIDE_RANGE_KEEP) == 0) {
        for (std::uint32_t p : partners) items.partnerBoxes.push_back(run.geometry.objectBox(p));
        r.partnerEnd = static_cast<std::uint32_t>(items.partnerBoxes.size());
    }
    items.objectRanges.push_back(r);
    items.objectItems += count;
}

/// A mesh's run of Cluster::levelGroups: its first group's first triangle in the mesh's spatial order, its groups and
/// their triangles.
struct GroupRun {
    std::uint32_t object = 0;
    std::uint32_t first = 0;
    std::uint32_t groups = 0;
    std::uint32_t triangles = 0;
};

/// The runs of `groups` (Cluster::levelGroups: one per mesh, in object order).
std::vector<GroupRun> groupRuns(const std::vector<Group>& groups) {
    std::vector<GroupRun> runs;
    for (const Group& g : groups) {
        if (runs.empty() || runs.back().object != g.object) runs.push_back(GroupRun{g.object, g.first, 0, 0});
        runs.back().groups += 1;
        runs.back().triangles += g.count;
    }
    return runs;
}

/// The group level described by its objects: the run of groups of each mesh of the cluster (Cluster::levelGroups;
/// a mesh's group boxes lie together), then one item per proxy. The device's box pre-pass keeps the groups whose box
/// meets a partner's object box; a proxy starts alive.
void addGroupRanges(LevelRun& run, const std::vector<std::uint32_t>& proxies) {
    const auto k = static_cast<std::uint32_t>(run.settings.groupSize);
    for (const GroupRun& r : groupRuns(run.cluster.levelGroups)) {
        // The run's first group is the mesh's (r.first / k)-th: its box that many after the mesh's first group's.
        const std::uint32_t firstBox = run.geometry.firstGroupBox(r.object) + r.first / k;
        addRange(run, r.object, r.groups, firstBox, 0, CULLIDE_RANGE_BOXES, kMaxGroupPartners);
    }
    for (std::uint32_t o : proxies)
        addRange(run, o, 1, run.geometry.objectBox(o), 0, CULLIDE_RANGE_BOXES | CULLIDE_RANGE_KEEP, 0);
    run.items.prepassSlack = run.geometry.prepassSlack(0.0);  // the boxes hold margin / 2 already
}

/// Partner ranges beyond which a mesh's triangles get no device exact stage: exact.comp's loop over them shares
/// llvmpipe's 65,535 iterations per invocation with its chunk's group pairs.
constexpr std::size_t kMaxExactPartners = 16384;

/// The device exact stage after the triangle level (LevelItems::exact): each mesh range's partners are the ranges of
/// its partner meshes with a larger object index (each object pair once). None where a range has too many partners,
/// more than 65,535 chunks of them, or groups too large (exactChunkItems).
void addExactRequest(LevelRun& run) {
    LevelItems& items = run.items;
    ExactRequest& x = items.exact;
    const std::vector<TriangleRange>& meshes = run.triangleRanges;  // the first ranges; the proxies' follow
    std::vector<std::uint32_t> rangeOfOwner(run.ownerCount, kNoOwner);
    for (std::size_t r = 0; r < meshes.size(); ++r)
        rangeOfOwner[run.ownerId[meshes[r].object]] = static_cast<std::uint32_t>(r);
    x.partnerBegin.assign(1, 0);
    std::size_t longest = 0;
    const auto k = static_cast<std::uint32_t>(run.settings.groupSize);
    for (std::size_t r = 0; r < items.objectRanges.size(); ++r) {
        std::size_t sum = 0;
        if (r < meshes.size()) {
            const std::uint32_t o = meshes[r].object;
            x.groupBoxes.push_back(run.geometry.firstGroupBox(o) + meshes[r].localFirst / k);  // its first group's
            for (std::uint32_t p : run.frame.partners[o]) {
                const std::uint32_t owner = run.ownerId[p];
                if (p < o || owner == kNoOwner || rangeOfOwner[owner] == kNoOwner) continue;
                x.partners.push_back(rangeOfOwner[owner]);
                sum += meshes[rangeOfOwner[owner]].count;
            }
        } else {
            x.groupBoxes.push_back(0);  // a proxy: no partners
        }
        if (x.partners.size() - x.partnerBegin.back() > kMaxExactPartners) {
            x.clear();
            return;
        }
        longest = std::max(longest, sum);
        x.partnerBegin.push_back(static_cast<std::uint32_t>(x.partners.size()));
    }
    x.chunkItems = exactChunkItems(static_cast<std::uint32_t>(run.settings.groupSize));
    if (x.chunkItems == 0) {  // groups too large for one invocation's loops
        x.clear();
        return;
    }
    x.chunks = static_cast<std::uint32_t>(std::max<std::size_t>(1, (longest + x.chunkItems - 1) / x.chunkItems));
    if (x.chunks > 65535) {  // a row of work groups per chunk
        x.clear();
        return;
    }
    x.run = true;
    x.filter = run.settings.exactTriangles;
    x.slack = exactSlack(run.settings.margin, run.geometry.origin(), run.geometry.coordinateBound());
    x.reach = exactReach(run.settings.margin, run.geometry.origin(), run.geometry.coordinateBound());
}

/// The triangle level described by its objects, inheriting the group level's survivors: every triangle of each
/// mesh's run of groups in its spatial order (its groups' one after the other), then the proxies. A triangle starts
/// alive where its group survived and its box meets a partner's object box (grown by margin / 2: triangle boxes are
/// not); a proxy where it survived. `exact`: the device exact stage follows it (addExactRequest).
void addTriangleRanges(LevelRun& run, const std::vector<std::uint32_t>& proxies, bool exact) {
    run.triangleRanges.clear();
    std::uint32_t parent = 0;  // the group level's item of the run's first group
    for (const GroupRun& r : groupRuns(run.cluster.levelGroups)) {
        const auto itemBegin = static_cast<std::uint32_t>(run.items.objectItems);
        run.triangleRanges.push_back({itemBegin, r.triangles, r.object, r.first});
        addRange(run, r.object, r.triangles, run.geometry.baseTriangle(r.object) + r.first, parent,
                 CULLIDE_RANGE_TRIANGLES, kMaxTrianglePartners);
        parent += r.groups;
    }
    for (std::uint32_t o : proxies)
        addRange(run, o, 1, run.geometry.objectBox(o), parent++, CULLIDE_RANGE_BOXES | CULLIDE_RANGE_KEEP, 0);
    run.items.inheritsParents = true;
    run.items.groupSize = static_cast<std::uint32_t>(run.settings.groupSize);
    run.items.prepassSlack = run.geometry.prepassSlack(0.5 * run.settings.margin);
    if (exact) addExactRequest(run);
}

/// The triangles of run.triangles and the proxies (occluders only) as one level; the surviving triangles go to
/// frame.surviving.
void runTriangleLevel(LevelRun& run, const std::vector<std::uint32_t>& proxies) {
    beginLevel(run);
    addTriangleItems(run, run.triangles);
    for (std::uint32_t o : proxies) addObjectBoxItem(run, o);
    prune(run, "triangles");
    run.backend.settle(run.stats);  // nothing pending unless a level run ahead found no level after it
    addSurvivingTriangles(run.frame, run.triangles, run.survivors);
}

/// Every triangle of every group of the cluster and the proxies as one level, which inherits the group level's
/// survivors on the backend: a triangle starts alive when its group survived and the box pre-pass keeps it, a proxy
/// when it survived. The surviving triangles go to frame.surviving — or, with `defer`, where the level reached the
/// backend (returns true), its read-back waits for the end of the frame (collectDeferred).
bool runInheritingTriangleLevel(LevelRun& run, const std::vector<std::uint32_t>& proxies, bool defer) {
    beginLevel(run, true);
    const DeviceExact where = run.settings.deviceExact;
    const bool exact =
        where == DeviceExact::Always || (where == DeviceExact::OnHardware && run.backend.hardwareDevice());
    addTriangleRanges(run, proxies, defer && exact);
    if (!defer) {
        prune(run, "triangles");
    } else if (pruneDeferred(run, "triangles")) {
        return true;
    }
    run.backend.settle(run.stats);  // a level run ahead that the triangle level did not wait for (no two owners)
    addSurvivingGroupTriangles(run.frame, run.cluster.levelGroups, run.survivors);
    return false;
}

std::size_t triangleCount(const std::vector<Group>& groups) {
    std::size_t n = 0;
    for (const Group& g : groups) n += g.count;
    return n;
}

/// CPU pre-pass (done in buildTriangleBoxesAndGroups), then the group level and the triangle level on the device, each
/// described by its objects (the device's pre-pass within each mesh's run of groups); a cluster whose kept triangles
/// are at most Settings::exactThreshold goes straight to the exact stage. `defer`: the
/// triangle level's read-back may wait for the end of the frame; returns true where it does.
bool runAutoPipeline(LevelRun& run, bool defer) {
    std::vector<std::uint32_t> proxies = clusterProxies(run);
    std::vector<Group> groups = run.cluster.groups;
    if (triangleCount(groups) > run.settings.exactThreshold) {
        beginLevel(run);
        addGroupRanges(run, proxies);
        if (pruneAhead(run, "groups")) {
            // The device goes on with the groups while the triangle level is described here.
            return runInheritingTriangleLevel(run, proxies, defer);
        }
        groups = run.cluster.levelGroups;  // the level's items; the CPU's pre-pass filters their triangles
        keepSurvivors(run.survivors, 0, groups);
        keepSurvivors(run.survivors, groups.size(), proxies);
    }
    collectTriangles(run.frame, groups, true, run.settings.margin, run.pool, run.scratch, run.triangles);
    if (run.triangles.size() > run.settings.exactThreshold)
        runTriangleLevel(run, proxies);
    else
        addSurvivingTriangles(run.frame, run.triangles, {});
    return false;
}

/// The paper's pipeline: objects as boxes, objects as triangles, groups as triangles, triangles.
void runPaperPipeline(LevelRun& run) {
    const FrameState& frame = run.frame;
    std::vector<std::uint32_t> objects = run.cluster.objects;
    beginLevel(run);
    for (std::uint32_t o : objects) addObjectBoxItem(run, o);
    prune(run, "objects-box");
    keepSurvivors(run.survivors, 0, objects);

    beginLevel(run);
    for (std::uint32_t o : objects) {
        if (frame.isMesh(o))
            addTriangleItem(run, o, frame.order[o]->data(), static_cast<std::uint32_t>(frame.order[o]->size()),
                            frame.valid[o].box);
        else
            addObjectBoxItem(run, o);
    }
    prune(run, "objects");
    keepSurvivors(run.survivors, 0, objects);
    std::vector<std::uint8_t> objectAlive(frame.valid.size(), 0);
    for (std::uint32_t o : objects) objectAlive[o] = 1;

    std::vector<Group> groups;
    for (const Group& g : run.cluster.groups)
        if (objectAlive[g.object]) groups.push_back(g);
    std::vector<std::uint32_t> proxies;
    for (std::uint32_t o : clusterProxies(run))
        if (objectAlive[o]) proxies.push_back(o);
    beginLevel(run);
    for (const Group& g : groups) addTriangleItem(run, g.object, &(*frame.order[g.object])[g.first], g.count, g.box);
    for (std::uint32_t o : proxies) addObjectBoxItem(run, o);
    prune(run, "groups");
    const std::size_t groupItems = groups.size();
    keepSurvivors(run.survivors, 0, groups);
    keepSurvivors(run.survivors, groupItems, proxies);
    collectTriangles(run.frame, groups, false, run.settings.margin, run.pool, run.scratch, run.triangles);
    runTriangleLevel(run, proxies);
}

/// Cluster::levelGroups from the cluster's kept groups (in object order, each object's in its order).
void levelGroupsOf(const FrameState& frame, const std::vector<Group>& kept, std::vector<Group>& levelGroups) {
    levelGroups.clear();
    for (std::size_t i = 0; i < kept.size();) {
        std::size_t last = i;
        while (last + 1 < kept.size() && kept[last + 1].object == kept[i].object) ++last;
        levelGroups.insert(levelGroups.end(), frame.allGroups.begin() + kept[i].index,
                           frame.allGroups.begin() + kept[last].index + 1);
        i = last + 1;
    }
}

bool rasterisable(const FrameState& frame, const Cluster& cluster) {
    Aabb box;
    for (std::uint32_t o : cluster.objects) box.grow(frame.valid[o].box);
    return box.isEmpty() || box.extent().maxCoeff() <= kRasterisableExtent;
}

}  // namespace

void LevelPipelines::addDevicePairs(FrameState& frame, const DeferredCluster& d,
                                    const std::vector<std::uint32_t>& words, Stats& stats) {
    const std::vector<TriangleRange>& ranges = d.exactRanges;
    // The object and triangle of a triangle item; BackendError where the device named an item of no range.
    auto triangleOf = [&](std::uint32_t item) {
        auto it = std::upper_bound(ranges.begin(), ranges.end(), item,
                                   [](std::uint32_t i, const TriangleRange& r) { return i < r.itemBegin; });
        if (it == ranges.begin() || item - (--it)->itemBegin >= it->count)
            throw BackendError("the device exact stage named an item of no triangle range");
        return std::make_pair(it->object, (*frame.order[it->object])[it->localFirst + (item - it->itemBegin)]);
    };
    std::size_t certified = 0;
    for (std::size_t w = 0; w + 1 < words.size(); w += 2) {
        auto [a, ta] = triangleOf(words[w]);
        auto [b, tb] = triangleOf(words[w + 1] & ~CULLIDE_EXACT_WITHIN);
        const bool within = (words[w + 1] & CULLIDE_EXACT_WITHIN) != 0;
        if (a == b) throw BackendError("the device exact stage paired an object with itself");
        if (b < a) {
            std::swap(a, b);
            std::swap(ta, tb);
        }
        frame.devicePairs.push_back({a, b, ta, tb, within});
        certified += within ? 1 : 0;
    }
    for (std::uint32_t o : d.cluster.objects) frame.exactOnDevice[o] = 1;
    stats.deviceExactClusters += 1;
    stats.deviceExactPairs += words.size() / 2;
    stats.deviceExactCertified += certified;
}

void LevelPipelines::run(FrameState& frame, const Settings& settings, PruningBackend& backend, TaskPool& pool,
                         TriangleScratch& scratch, Stats& stats) {
    frame.devicePairs.clear();
    frame.exactOnDevice.assign(frame.valid.size(), 0);
    backend.beginFrame();
    m_deferred.clear();
    m_geometry.beginFrame();
    const std::vector<std::vector<std::uint32_t>> clusters = clustersOf(frame.active, frame.pairs, frame.valid);
    stats.clusters += clusters.size();
    std::size_t place = 0;  // the frame's levels so far
    std::vector<std::uint8_t> member(frame.valid.size(), 0);
    Cluster cluster;
    for (const std::vector<std::uint32_t>& objects : clusters) {
        for (std::uint32_t o : objects) member[o] = 1;
        cluster.objects = objects;
        cluster.groups.clear();
        for (const Group& g : frame.groups)
            if (member[g.object]) cluster.groups.push_back(g);
        levelGroupsOf(frame, cluster.groups, cluster.levelGroups);
        for (std::uint32_t o : objects) member[o] = 0;
        if (!rasterisable(frame, cluster)) {
            // Relative coordinates beyond what float positions and depths carry: no pruning (sound, and rare).
            ++stats.unrasterisedClusters;
            collectTriangles(frame, cluster.groups, true, settings.margin, pool, scratch, m_triangles);
            addSurvivingTriangles(frame, m_triangles, {});
            continue;
        }
        const std::size_t firstPlace = place, firstLevel = stats.levels.size();
        if (runCluster(frame, cluster, settings, backend, pool, scratch, stats, place, true)) {
            m_deferred.push_back(DeferredCluster{cluster, firstPlace, firstLevel, stats.levels.size(), {}});
            if (m_items.exact.run) m_deferred.back().exactRanges = m_triangleRanges;
        }
    }
    collectDeferred(frame, settings, backend, pool, scratch, stats);
}

bool LevelPipelines::runCluster(FrameState& frame, const Cluster& cluster, const Settings& settings,
                                PruningBackend& backend, TaskPool& pool, TriangleScratch& scratch, Stats& stats,
                                std::size_t& place, bool defer) {
    LevelRun run{frame, cluster, settings, backend, pool, scratch, stats, m_geometry, m_items,
                 m_survivors, m_ownerId, m_triangles, place, m_triangleRanges};
    const std::size_t firstPlace = place;
    const std::size_t firstLevel = stats.levels.size();
    for (int attempt = 0;; ++attempt) {
        try {
            if (settings.pipeline == Pipeline::Paper) {
                runPaperPipeline(run);
                return false;
            }
            return runAutoPipeline(run, defer);
        } catch (const LevelsRerun&) {  // the backend now waits for the level it ran ahead
            if (attempt == 1) throw BackendError("a level run ahead stopped early twice");
            ++stats.levelReruns;  // the frame's totals keep what the first attempt cost; its levels go
            place = firstPlace;
            stats.levels.resize(firstLevel);
        }
    }
}

void LevelPipelines::collectDeferred(FrameState& frame, const Settings& settings, PruningBackend& backend,
                                     TaskPool& pool, TriangleScratch& scratch, Stats& stats) {
    if (m_deferred.empty()) return;
    // One wait for every cluster; a trial frame (or a run with a budget) waits no longer than its deadline.
    if (!backend.collect(Deadline::earlier(frame.levelsDeadline, frame.runDeadline), m_results, stats)) {
        if (frame.runDeadline.expired()) throw RunAbandoned{};
        throw LevelsAbandoned{};
    }
    if (m_results.size() != m_deferred.size()) throw BackendError("the deferred levels were not all collected");
    std::ptrdiff_t shift = 0;  // levels that reruns added, less those they replaced: where later clusters' now are
    for (std::size_t k = 0; k < m_deferred.size(); ++k) {
        const DeferredCluster& d = m_deferred[k];
        if (m_results[k].complete) {
            addSurvivingGroupTriangles(frame, d.cluster.levelGroups, m_results[k].survivors);
            if (m_results[k].exactRan) addDevicePairs(frame, d, m_results[k].exactPairs, stats);
            continue;
        }
        // A chain stopped early on the device (records to build again, more iterations than were issued): the
        // cluster runs again, waited for, and its levels replace the first attempt's (the frame's totals keep what
        // that cost).
        ++stats.levelReruns;
        const auto first = stats.levels.begin() + static_cast<std::ptrdiff_t>(d.firstLevel) + shift;
        stats.levels.erase(first, first + static_cast<std::ptrdiff_t>(d.endLevel - d.firstLevel));
        const std::size_t rerunFrom = stats.levels.size();
        std::size_t place = d.firstPlace;
        runCluster(frame, d.cluster, settings, backend, pool, scratch, stats, place, false);
        const std::size_t added = stats.levels.size() - rerunFrom;
        std::rotate(stats.levels.begin() + static_cast<std::ptrdiff_t>(d.firstLevel) + shift,
                    stats.levels.begin() + static_cast<std::ptrdiff_t>(rerunFrom), stats.levels.end());
        shift += static_cast<std::ptrdiff_t>(added) - static_cast<std::ptrdiff_t>(d.endLevel - d.firstLevel);
    }
}

}  // namespace cullide
