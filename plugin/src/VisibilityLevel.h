// One CULLIDE level (objects, groups or triangles) as a loop of visibility iterations, and the pure functions it is
// made of: the view fitted to the alive items with its float-error bounds (docs/reliability.md, section 7), the
// owner-id packing and the survival rule. No GL: the iterations run on any PruningBackend.
#pragma once

#include "PruningBackend.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <vector>

namespace cullide {

/// The view of an iteration over items whose bounds are `bounds` (relative to the upload origin): the box grown by
/// half the margin (each item is dilated by half: together the full margin), 1e-4 of its extent and 2^-22 of the
/// largest coordinate (the rounding of the float vertices that later iterations' bounds are made of), no axis
/// thinner than 1e-6 of the largest, and per world axis the float parameters of the shaders. The reliable-mode slack
/// (halfSize beyond half a pixel plus the margin, depthPad beyond the margin) covers the float error of positions
/// up to `coordinateBound` from the origin and of the projection: 2^-18 (1 + B / extent) with B the larger of
/// coordinateBound and the box's own coordinates.
View fitView(const Aabb& bounds, const Settings& settings, double coordinateBound);

/// Bits of the packed per-pixel value that hold the owner id: enough for `maxOwner`, at least 1, at most 31.
std::uint32_t idBitsFor(std::uint32_t maxOwner);

/// Depth bits beside `idBits` owner bits (at most 24: a float holds the scale exactly).
std::uint32_t depthBitsFor(std::uint32_t idBits);

/// The flag bits an item needs to stay alive: both view directions of every enabled axis (Settings::axes).
std::uint32_t requiredFlags(unsigned axes);

/// Distinct owners among the items, or 0 when owner ids need more than 16 bits (the level then prunes nothing).
std::size_t distinctOwners(const LevelItems& items);

/// The box of item `i` as the device builds it (build.comp): over its primitives as uploaded (float vertices, float
/// boxes), so exact in float. The iterations after the first fit their views to these (IterationResult::bounds).
Aabb deviceBoundsOf(const GpuGeometry& geometry, const LevelItems& items, std::size_t i);

/// What follows an iteration of a level.
enum class Step {
    Next,       ///< the next iteration runs, with the view fitted to what this one left
    Stop,       ///< the level ends with the items alive now
    AllPruned,  ///< one owner is left: nothing to collide with, the level ends with every item pruned
};

/// The stop rule after iteration `iteration` (from 0) of a level, which left `r` of `aliveBefore` items alive: stop
/// when it pruned nothing (an overflow; the set only shrinks, so the same size is the same set) or left none; all
/// pruned when one owner is left; stop when it pruned less than Settings::minPruneFraction of them, and after
/// Settings::maxIterations. survive.comp's finishIteration is its GLSL twin.
Step stepAfter(const IterationResult& r, std::size_t aliveBefore, int iteration, const Settings& settings);

/// Adds an iteration to the level's stats: the iteration itself, and the items after it in itemsPerIteration where
/// it changed the set (and a 0 after them when the level ends all pruned).
void noteIteration(LevelStats& level, std::size_t aliveBefore, std::size_t aliveAfter, Step step);

/// Runs one level on `backend`: survivors[i] is 1 when item i may intersect an item of another owner. At most
/// Settings::maxIterations iterations, each fitted to the items still alive, until stepAfter says stop
/// (PruningBackend::pruneLevel); a level without two owners ends at once. `coordinateBound`:
/// GpuGeometry::coordinateBound of the upload the items refer to; `place`: the level's place in the frame.
void pruneLevel(PruningBackend& backend, const LevelItems& items, const Settings& settings, double coordinateBound,
                std::size_t place, std::vector<std::uint8_t>& survivors, LevelStats& level, Stats& stats);

/// pruneLevel with the survivors left on the backend for the next level's items to inherit
/// (PruningBackend::pruneLevelAhead; the level's stats are stats.levels[levelIndex]). Returns false where the level
/// did not reach the backend (no two owners): `survivors` then says which items survive, and the next level cannot
/// inherit them.
bool pruneLevelAhead(PruningBackend& backend, const LevelItems& items, const Settings& settings,
                     double coordinateBound, std::size_t place, std::vector<std::uint8_t>& survivors,
                     std::size_t levelIndex, Stats& stats);

/// pruneLevel with the read-back deferred (PruningBackend::pruneLevelDeferred; the level's stats are
/// stats.levels[levelIndex], complete after PruningBackend::collect). Returns false where the level did not reach the
/// backend (it ends at once): `survivors` then says which items survive.
bool pruneLevelDeferred(PruningBackend& backend, const LevelItems& items, const Settings& settings,
                        double coordinateBound, std::size_t place, std::vector<std::uint8_t>& survivors,
                        std::size_t levelIndex, Stats& stats);

}  // namespace cullide
