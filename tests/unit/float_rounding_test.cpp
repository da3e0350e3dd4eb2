// The outward float rounding the exact stage's float boxes rely on (FloatRounding.h): floatDown/floatUp are the
// nearest floats on their side of any double, floatBelow/floatAbove on their side within a few ulps.
#include "FloatRounding.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace cullide {
namespace {

TEST(FloatRounding, OutwardForEveryMagnitude) {
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
    std::uniform_int_distribution<int> exponent(-160, 160);
    std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 1e-45, -1e-45, 1e-310, -1e-310, 3.4028234663852886e38,
                                  -3.4028234663852886e38, 3.5e38, -3.5e38, 1e300, -1e300, 0.1, -0.1};
    for (int i = 0; i < 100000; ++i) values.push_back(std::ldexp(mantissa(rng), exponent(rng)));
    for (const double v : values) {
        ASSERT_LE(static_cast<double>(floatDown(v)), v) << v;
        ASSERT_GE(static_cast<double>(floatUp(v)), v) << v;
        ASSERT_LE(static_cast<double>(floatBelow(v)), v) << v;
        ASSERT_GE(static_cast<double>(floatAbove(v)), v) << v;
        // floatDown / floatUp are the nearest floats on their side: the next float beyond is past v.
        const float down = floatDown(v);
        const float up = floatUp(v);
        if (std::isfinite(down) && down < std::numeric_limits<float>::max()) {
            ASSERT_GT(static_cast<double>(std::nextafter(down, std::numeric_limits<float>::infinity())), v) << v;
        }
        if (std::isfinite(up) && up > -std::numeric_limits<float>::max()) {
            ASSERT_LT(static_cast<double>(std::nextafter(up, -std::numeric_limits<float>::infinity())), v) << v;
        }
        // floatBelow / floatAbove stay within a few ulps inside the float range.
        if (std::fabs(v) < 1e38 && std::fabs(v) > 1e-30) {  // a few ulps: well under 1e-6 relative
            ASSERT_LE(std::fabs(static_cast<double>(floatBelow(v)) - v), std::fabs(v) * 1e-6) << v;
            ASSERT_LE(std::fabs(static_cast<double>(floatAbove(v)) - v), std::fabs(v) * 1e-6) << v;
        }
    }
}

}  // namespace
}  // namespace cullide
