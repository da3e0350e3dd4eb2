// The device exact stage's parameters and its CPU copy: the candidate pairs among a deferred triangle level's
// survivors and the filter's verdicts (shaders/exact.comp; DeviceExactFilter.h), as the reference backend computes
// them and the GL tests hold the device to.
#pragma once

#include "PruningBackend.h"
#include "cullide/Types.h"

#include <cstdint>
#include <vector>

namespace cullide {

/// The most triangle pairs one exact.comp invocation may visit (a chunk's partner items times its group's
/// triangles), within llvmpipe's 65,535 loop iterations per invocation.
constexpr std::size_t kMostExactGroupPairWork = 32768;

/// Partner items per chunk of exact.comp for groups of `groupSize`: whole groups, as many as kMostExactGroupPairWork
/// allows (0: groups too large for the device exact stage).
std::uint32_t exactChunkItems(std::uint32_t groupSize);

/// How far exact.comp grows a triangle's box (of the positions, float) before it compares it with another's: the
/// margin (both halves) and, for each of the two boxes, the float error of the positions (2^-20 of the largest
/// coordinate) and the double error of world - origin (2^-48 of the largest world coordinate), rounded up — so that
/// every pair whose double boxes, grown by margin / 2, overlap is compared.
float exactSlack(double margin, const Vec3& origin, double coordinateBound);

/// The filter's reach (DeviceExactFilter.h): 0 for margin 0 (the CPU's test is then exact intersection), otherwise
/// the margin plus a bound of the CPU's double distance error (2^-20 of the largest world coordinate and of the
/// margin: generous, since a sliver's face normal may tilt), rounded up: a pair certified farther apart than this is
/// farther than the margin by the CPU's test too.
float exactReach(double margin, const Vec3& origin, double coordinateBound);

/// exact.comp on the CPU: the pairs of surviving triangle items (alive[i] != 0) of `items`' ranges and their exact
/// partners (items.exact), item i being triangle prims[i] of `indices` over `positions` (the device's floats), in the
/// order exact.comp's invocations would write them one at a time: two words each, the second |
/// CULLIDE_EXACT_WITHIN where the filter certified the pair.
void findExactPairs(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices,
                    const LevelItems& items, const std::vector<std::uint32_t>& prims,
                    const std::vector<std::uint8_t>& alive, std::vector<std::uint32_t>& pairs);

}  // namespace cullide
