#include "DeviceExact.h"

#include "DeviceExactFilter.h"
#include "FloatRounding.h"
#include "bindings.h"

#include <algorithm>
#include <cmath>

namespace cullide {

std::uint32_t exactChunkItems(std::uint32_t groupSize) {
    if (groupSize == 0) return 0;
    const std::size_t groups = kMostExactGroupPairWork / (std::size_t{groupSize} * groupSize);
    return static_cast<std::uint32_t>(groups * groupSize);
}

float exactSlack(double margin, const Vec3& origin, double coordinateBound) {
    const double world = origin.cwiseAbs().maxCoeff() + coordinateBound;
    return floatUp(margin + 2.0 * (std::ldexp(coordinateBound, -20) + std::ldexp(world, -48)));
}

float exactReach(double margin, const Vec3& origin, double coordinateBound) {
    if (!(margin > 0.0)) return 0.0f;
    const double world = origin.cwiseAbs().maxCoeff() + coordinateBound;
    return floatUp(margin + std::ldexp(world + margin, -20));
}

namespace {

struct Triangle {
    float v[3][3];
    float lo[3];
    float hi[3];
};

Triangle triangleOf(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices, std::uint32_t t) {
    Triangle tri{};
    for (int k = 0; k < 3; ++k) {
        const std::size_t at = 3 * std::size_t{indices.at(3 * std::size_t{t} + k)};
        for (int a = 0; a < 3; ++a) tri.v[k][a] = positions.at(at + a);
    }
    for (int a = 0; a < 3; ++a) {
        tri.lo[a] = std::min(std::min(tri.v[0][a], tri.v[1][a]), tri.v[2][a]);
        tri.hi[a] = std::max(std::max(tri.v[0][a], tri.v[1][a]), tri.v[2][a]);
    }
    return tri;
}

/// exact.comp's box test: b's box meets a's grown by `slack`.
bool boxesMeet(const Triangle& a, const Triangle& b, float slack) {
    for (int x = 0; x < 3; ++x) {
        const float lo = a.lo[x] - slack;
        const float hi = a.hi[x] + slack;
        if (!(lo <= b.hi[x]) || !(b.lo[x] <= hi)) return false;
    }
    return true;
}

FilterVerdict verdictOf(const Triangle& a, const Triangle& b, const ExactRequest& request) {
    if (!request.filter) return FilterVerdict::Uncertain;
    float v[6][3];
    for (int k = 0; k < 3; ++k)
        for (int x = 0; x < 3; ++x) {
            v[k][x] = a.v[k][x];
            v[3 + k][x] = b.v[k][x];
        }
    return filterTrianglePair(v, request.reach);
}

}  // namespace

void findExactPairs(const std::vector<float>& positions, const std::vector<std::uint32_t>& indices,
                    const LevelItems& items, const std::vector<std::uint32_t>& prims,
                    const std::vector<std::uint8_t>& alive, std::vector<std::uint32_t>& pairs) {
    pairs.clear();
    const ExactRequest& request = items.exact;
    if (!request.run) return;
    for (std::size_t r = 0; r < items.objectRanges.size(); ++r) {
        const ObjectRange& range = items.objectRanges[r];
        if ((range.kind & 1u) != CULLIDE_RANGE_TRIANGLES) continue;
        for (std::uint32_t j = 0; j < range.count; ++j) {
            const std::uint32_t i = range.itemBegin + j;
            if (alive.at(i) == 0) continue;
            const Triangle a = triangleOf(positions, indices, prims.at(i));
            for (std::uint32_t p = request.partnerBegin.at(r); p < request.partnerBegin.at(r + 1); ++p) {
                const ObjectRange& other = items.objectRanges.at(request.partners.at(p));
                for (std::uint32_t k = 0; k < other.count; ++k) {
                    const std::uint32_t item = other.itemBegin + k;
                    if (alive.at(item) == 0) continue;
                    const Triangle b = triangleOf(positions, indices, prims.at(item));
                    if (!boxesMeet(a, b, request.slack)) continue;
                    const FilterVerdict verdict = verdictOf(a, b, request);
                    if (verdict == FilterVerdict::Apart) continue;
                    pairs.push_back(i);
                    pairs.push_back(item | (verdict == FilterVerdict::Within ? CULLIDE_EXACT_WITHIN : 0u));
                }
            }
        }
    }
}

}  // namespace cullide
