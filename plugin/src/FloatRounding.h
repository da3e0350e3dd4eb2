// Outward rounding of doubles to float: a float box built with these contains the double box it came from.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace cullide {
namespace detail {

/// The next float towards -inf (towards +inf with `up`) of a finite f, by its bit pattern (no libm call: this runs
/// for every triangle box of every frame).
inline float nextFloat(float f, bool up) {
    if (f == 0.0f) return up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
    std::uint32_t bits = 0;
    std::memcpy(&bits, &f, sizeof bits);
    const bool positive = (bits >> 31) == 0;
    bits = positive == up ? bits + 1 : bits - 1;  // away from zero when moving in the sign's direction
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

}  // namespace detail

/// The largest float <= v (-inf below the float range).
inline float floatDown(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    if (v > kMax) return std::numeric_limits<float>::max();
    if (v < -kMax) return -std::numeric_limits<float>::infinity();
    const auto f = static_cast<float>(v);
    return static_cast<double>(f) > v ? detail::nextFloat(f, false) : f;
}

/// The smallest float >= v (+inf above the float range).
inline float floatUp(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    if (v > kMax) return std::numeric_limits<float>::infinity();
    if (v < -kMax) return -std::numeric_limits<float>::max();
    const auto f = static_cast<float>(v);
    return static_cast<double>(f) < v ? detail::nextFloat(f, true) : f;
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
