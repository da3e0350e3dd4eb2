// Outward rounding of doubles to float: a float box built with these contains the double box it came from.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace cullide {
namespace detail {

/// The float's bit pattern and back.
inline std::uint32_t floatBits(float f) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &f, sizeof bits);
    return bits;
}
inline float fromFloatBits(std::uint32_t bits) {
    float f = 0.0f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

}  // namespace detail

/// The largest float <= v (-inf below the float range). Without branches: whether float(v) rounded up is a coin
/// toss per coordinate, so a branch on it is mispredicted half the time (millions of calls a frame in the GPU
/// levels' set-up). The next float down of f, when f > v: one step of the bits towards zero for f > 0, away from
/// it for f < 0 (-0 included: its next is -denorm_min); f = +0 never needs it (then v >= 0).
inline float floatDown(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    const auto f = static_cast<float>(std::min(std::max(v, -kMax), kMax));  // v < -kMax: -FLT_MAX, then -inf below
    const std::uint32_t bits = detail::floatBits(f);
    // An integer product, not a select: compilers turn `f > v ? below : f` back into a branch.
    const auto needed = static_cast<std::uint32_t>(static_cast<double>(f) > v);
    return detail::fromFloatBits(bits + needed * (2 * (bits >> 31) - 1));
}

/// The smallest float >= v (+inf above the float range); as floatDown, mirrored (+0's next is denorm_min; f = -0
/// never needs it).
inline float floatUp(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    const auto f = static_cast<float>(std::min(std::max(v, -kMax), kMax));
    const std::uint32_t bits = detail::floatBits(f);
    const auto needed = static_cast<std::uint32_t>(static_cast<double>(f) < v);
    return detail::fromFloatBits(bits + needed * (1 - 2 * (bits >> 31)));
}

/// A float below v, within a few float ulps, without branches (the bulk path: every triangle box of a frame).
/// float(v) is within half an ulp of v and an ulp is at most |f| * 2^-23, so moving at least two ulps (plus the
/// smallest denormal, for f near zero) lands below v whatever the rounding of the subtraction. Beyond the float
/// range the result is -inf or -FLT_MAX.
inline float floatBelow(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    const auto f = static_cast<float>(std::clamp(v, -kMax, kMax));
    return f - (std::fabs(f) * 0x1p-22f + std::numeric_limits<float>::denorm_min());
}

/// A float above v, within a few float ulps (see floatBelow).
inline float floatAbove(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    const auto f = static_cast<float>(std::clamp(v, -kMax, kMax));
    return f + (std::fabs(f) * 0x1p-22f + std::numeric_limits<float>::denorm_min());
}

}  // namespace cullide
