// What a GL back-end takes as a level's items (PruningBackend::pruneLevel's contract): the compute back-end decides
// an item when its last record is done, so an item without primitives, which has no record, is refused with a
// BackendError (the culler then finishes the frame on the CPU) instead of being left alive and uncounted; so is a
// level described by its objects whose ranges leave an item out or name what the upload does not hold.
#include "CullerBackends.h"
#include "GlTestSupport.h"
#include "PruningBackend.h"
#include "VisibilityLevel.h"
#include "bindings.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace cullide::test {
namespace {

/// Two unit boxes, overlapping, as one upload.
GpuGeometry twoBoxes() {
    GpuGeometry g;
    g.boxes = {0, 0, 0, 1, 1, 1, 0.5f, 0.5f, 0.5f, 1.5f, 1.5f, 1.5f};
    g.coordinateBound = 1.5;
    return g;
}

LevelItems boxItems(bool withEmptyItem) {
    LevelItems items;
    const auto add = [&](std::uint32_t owner, std::vector<std::uint32_t> prims, const Aabb& box) {
        items.owner.push_back(owner);
        items.prims.insert(items.prims.end(), prims.begin(), prims.end());
        items.primBegin.push_back(static_cast<std::uint32_t>(items.prims.size()));
        items.bounds.push_back(box);
    };
    const Aabb first{Vec3(0, 0, 0), Vec3(1, 1, 1)}, second{Vec3(0.5, 0.5, 0.5), Vec3(1.5, 1.5, 1.5)};
    add(0, {0u | CULLIDE_PRIM_BOX_BIT}, first);
    if (withEmptyItem) add(1, {}, second);
    add(1, {1u | CULLIDE_PRIM_BOX_BIT}, second);
    return items;
}

/// Settings that run every level, on the compute back-end.
Settings levelSettings() {
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;
    settings.backend = Backend::Compute;
    settings.resolution = 64;
    return settings;
}

/// The two boxes uploaded to a GL back-end; each level run over them.
struct TwoBoxesOnTheDevice {
    explicit TwoBoxesOnTheDevice(const Settings& s) : settings(s), backend(createGlPruningBackend(s)) {
        backend->upload(geometry, stats);
    }
    /// Whether the back-end took `items` (no BackendError); `survivors` as it left them.
    bool run(const LevelItems& items, std::vector<std::uint8_t>& survivors) {
        stats.levels.assign(1, LevelStats{});
        try {
            pruneLevel(*backend, items, settings, geometry.coordinateBound, 0, survivors, stats.levels[0], stats);
            return true;
        } catch (const BackendError&) {
            return false;
        }
    }
    Settings settings;
    GpuGeometry geometry = twoBoxes();
    std::unique_ptr<PruningBackend> backend;
    Stats stats;
};

TEST(LevelItems, TheComputeBackEndRefusesAnItemWithoutPrimitives) {
    CULLIDE_GPU_CULLER_OR_SKIP(probe, levelSettings());
    TwoBoxesOnTheDevice device(levelSettings());
    for (const bool withEmptyItem : {false, true}) {
        std::vector<std::uint8_t> survivors;
        const bool taken = device.run(boxItems(withEmptyItem), survivors);
        EXPECT_EQ(taken, !withEmptyItem);
        if (!taken) continue;
        EXPECT_EQ(survivors, (std::vector<std::uint8_t>{1, 1})) << "they overlap";
    }
}

/// The two boxes as a level described by its objects: a range each, the other's box its partner. `breakIt`
/// breaks one thing: start.comp would read out of bounds or miss an item.
LevelItems boxRanges(int breakIt) {
    LevelItems items;
    for (std::uint32_t o = 0; o < 2; ++o) {
        ObjectRange r;
        r.itemBegin = o;
        r.count = 1;
        r.first = o;
        r.owner = o;
        r.kind = CULLIDE_RANGE_BOXES;
        r.partnerBegin = o;
        r.partnerEnd = o + 1;
        items.objectRanges.push_back(r);
        items.partnerBoxes.push_back(1 - o);
    }
    items.objectItems = 2;
    if (breakIt == 1) items.objectRanges[1].itemBegin = 2;  // a gap: item 1 in no range
    if (breakIt == 2) items.objectRanges[1].first = 2;      // a box the upload does not hold
    if (breakIt == 3) items.partnerBoxes[0] = 7;             // a partner box it does not hold either
    if (breakIt == 4) items.objectItems = 3;                 // more items than the ranges cover
    if (breakIt == 5) items.groupSize = 0;                   // no triangle per parent
    return items;
}

TEST(LevelItems, ALevelDescribedByItsObjectsIsRefusedWhereItsRangesDoNotFit) {
    CULLIDE_GPU_CULLER_OR_SKIP(probe, levelSettings());
    TwoBoxesOnTheDevice device(levelSettings());
    for (int breakIt = 0; breakIt <= 5; ++breakIt) {
        std::vector<std::uint8_t> survivors;
        const bool taken = device.run(boxRanges(breakIt), survivors);
        EXPECT_EQ(taken, breakIt == 0) << breakIt;
        if (!taken) continue;
        EXPECT_EQ(survivors, (std::vector<std::uint8_t>{1, 1})) << "they overlap";
        EXPECT_EQ(device.stats.levels[0].itemsPerIteration.front(), 2u) << "each meets its partner: both start alive";
    }
}

}  // namespace
}  // namespace cullide::test
