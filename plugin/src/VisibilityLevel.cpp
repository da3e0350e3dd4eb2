#include "VisibilityLevel.h"

#include "bindings.h"
#include "KeptCapacity.h"
#include "cullide/Timer.h"

#include <algorithm>
#include <cmath>

namespace cullide {

View fitView(const Aabb& bounds, const Settings& settings, double coordinateBound) {
    View v;
    const double margin = 0.5 * settings.margin;
    const double scale = std::max(bounds.extent().maxCoeff(), 1e-30);
    // After the first iteration the bounds are the boxes of the uploaded float vertices (deviceBoundsOf), rounded to
    // nearest: a true vertex may lie half an ulp of its coordinate outside. 2^-22 of the largest coordinate is more.
    const double largest = std::max(coordinateBound, bounds.min.cwiseAbs().cwiseMax(bounds.max.cwiseAbs()).maxCoeff());
    v.box = bounds.inflated(margin + 1e-4 * scale + std::ldexp(largest, -22));
    Vec3 extent = v.box.extent();
    const double minExtent = std::max(1e-6 * extent.maxCoeff(), 1e-30);
    for (int a = 0; a < 3; ++a) {
        if (extent[a] < minExtent) {
            v.box.min[a] -= 0.5 * minExtent;
            v.box.max[a] += 0.5 * minExtent;
        }
    }
    extent = v.box.extent();
    const double res = settings.resolution;
    const double bound = std::max(coordinateBound, v.box.min.cwiseAbs().cwiseMax(v.box.max.cwiseAbs()).maxCoeff());
    for (int a = 0; a < 3; ++a) {
        // Float error of positions (relative to the origin) and of the projection, as a fraction of the extent: a
        // few ulps of `bound`, generously over-estimated (docs/reliability.md).
        const double relative = std::ldexp(1.0, -18) * (1.0 + bound / extent[a]);
        v.lo[a] = static_cast<float>(v.box.min[a]);
        v.pixelScale[a] = static_cast<float>(res / extent[a]);
        v.depthScale[a] = static_cast<float>(1.0 / extent[a]);
        v.halfSize[a] = static_cast<float>(0.5 + margin * res / extent[a] + 1e-3 + relative * res);
        v.depthPad[a] = static_cast<float>(margin / extent[a] + relative + std::ldexp(1.0, -20));
    }
    return v;
}

std::uint32_t idBitsFor(std::uint32_t maxOwner) {
    std::uint32_t bits = 1;
    while (bits < 31 && (maxOwner >> bits) != 0) ++bits;
    return bits;
}

std::uint32_t depthBitsFor(std::uint32_t idBits) { return std::min(24u, 32u - idBits); }

std::uint32_t requiredFlags(unsigned axes) {
    std::uint32_t required = 0;
    for (unsigned a = 0; a < 3; ++a)
        if (axes & (1u << a)) required |= 3u << (2 * a);
    return required;
}

std::size_t distinctOwners(const LevelItems& items) {
    if (items.size() == 0) return 0;
    std::vector<std::uint32_t> rangeOwners;  // a level described by its objects: an owner per range
    for (const ObjectRange& r : items.objectRanges)
        if (r.count > 0) rangeOwners.push_back(r.owner);
    const std::vector<std::uint32_t>& owners = items.describedByObjects() ? rangeOwners : items.owner;
    const std::uint32_t maxOwner = *std::max_element(owners.begin(), owners.end());
    if (maxOwner >= 65536) return 0;
    std::vector<std::uint8_t> seen(maxOwner + std::size_t{1}, 0);
    std::size_t distinct = 0;
    for (std::uint32_t o : owners) {
        if (!seen[o]) ++distinct;
        seen[o] = 1;
    }
    return distinct;
}

Aabb deviceBoundsOf(const GpuGeometry& geometry, const LevelItems& items, std::size_t i) {
    Aabb b;
    for (std::uint32_t p = items.primBegin[i]; p < items.primBegin[i + 1]; ++p) {
        const std::uint32_t ref = items.prims[p];
        if (ref & CULLIDE_PRIM_BOX_BIT) {
            const float* f = &geometry.boxes[6 * std::size_t{ref & ~CULLIDE_PRIM_BOX_BIT}];
            b.grow(Vec3(f[0], f[1], f[2]));
            b.grow(Vec3(f[3], f[4], f[5]));
            continue;
        }
        for (std::size_t k = 0; k < 3; ++k) {
            const float* v = &geometry.positions[3 * std::size_t{geometry.indices[3 * std::size_t{ref} + k]}];
            b.grow(Vec3(v[0], v[1], v[2]));
        }
    }
    return b;
}

Step stepAfter(const IterationResult& r, std::size_t aliveBefore, int iteration, const Settings& settings) {
    if (r.overflows != 0 || r.alive == aliveBefore || r.alive == 0) return Step::Stop;
    if (r.ownerMin == r.ownerMax) return Step::AllPruned;
    const double pruned = static_cast<double>(aliveBefore - r.alive);
    if (pruned < settings.minPruneFraction * static_cast<double>(aliveBefore)) return Step::Stop;
    return iteration + 1 >= settings.maxIterations ? Step::Stop : Step::Next;
}

void noteIteration(LevelStats& level, std::size_t aliveBefore, std::size_t aliveAfter, Step step) {
    ++level.iterations;
    if (aliveAfter == aliveBefore) return;
    level.itemsPerIteration.push_back(aliveAfter);
    if (step == Step::AllPruned) level.itemsPerIteration.push_back(0);
}

namespace {

/// What the backend needs to run a level; false (survivors set, stats noted) where the level ends at once: no items,
/// one owner (nothing to collide with: all pruned), or owner ids over 16 bits (no pruning, conservative).
bool startLevel(const LevelItems& items, const Settings& settings, double coordinateBound, std::size_t place,
                std::vector<std::uint8_t>& survivors, LevelStats& level, LevelStart& start) {
    const std::size_t n = items.size();
    assignKeeping(survivors, n, std::uint8_t{1});
    if (n == 0) return false;
    level.itemsPerIteration.push_back(n);
    const std::size_t owners = distinctOwners(items);
    if (owners == 0) return false;
    if (owners < 2) {
        std::fill(survivors.begin(), survivors.end(), 0);
        level.itemsPerIteration.push_back(0);
        return false;
    }
    start.coordinateBound = coordinateBound;
    start.place = place;
    if (items.describedByObjects()) return true;  // the backend finds the items that start alive and fits the view
    Aabb bounds;
    for (const Aabb& b : items.bounds) bounds.grow(b);
    if (bounds.isEmpty()) {  // no item has a box: nothing to run
        std::fill(survivors.begin(), survivors.end(), 0);
        level.itemsPerIteration.push_back(0);
        return false;
    }
    start.view = fitView(bounds, settings, coordinateBound);
    start.idBits = idBitsFor(*std::max_element(items.owner.begin(), items.owner.end()));
    return true;
}

}  // namespace

void pruneLevel(PruningBackend& backend, const LevelItems& items, const Settings& settings, double coordinateBound,
                std::size_t place, std::vector<std::uint8_t>& survivors, LevelStats& level, Stats& stats) {
    const Timer timer;
    LevelStart start;
    if (startLevel(items, settings, coordinateBound, place, survivors, level, start))
        backend.pruneLevel(items, start, survivors, level, stats, nullptr);
    level.cpuMs += timer.ms();
}

bool pruneLevelAhead(PruningBackend& backend, const LevelItems& items, const Settings& settings,
                     double coordinateBound, std::size_t place, std::vector<std::uint8_t>& survivors,
                     std::size_t levelIndex, Stats& stats) {
    const Timer timer;
    LevelStart start;
    const bool ahead = startLevel(items, settings, coordinateBound, place, survivors, stats.levels[levelIndex], start);
    if (ahead) backend.pruneLevelAhead(items, start, levelIndex, stats, nullptr);
    stats.levels[levelIndex].cpuMs += timer.ms();
    return ahead;
}

bool pruneLevelDeferred(PruningBackend& backend, const LevelItems& items, const Settings& settings,
                        double coordinateBound, std::size_t place, std::vector<std::uint8_t>& survivors,
                        std::size_t levelIndex, Stats& stats) {
    const Timer timer;
    LevelStart start;
    const bool deferred =
        startLevel(items, settings, coordinateBound, place, survivors, stats.levels[levelIndex], start);
    if (deferred) backend.pruneLevelDeferred(items, start, levelIndex, stats, nullptr);
    stats.levels[levelIndex].cpuMs += timer.ms();
    return deferred;
}

}  // namespace cullide
