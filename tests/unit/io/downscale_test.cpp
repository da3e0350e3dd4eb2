// The box downscale (Image.h): blocks averaged with rounding, partial edge blocks, factor one and large factors,
// invalid arguments.
#include "ImageSupport.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace cullide::io {
namespace {

using namespace cullide::test;

// ---------------------------------------------------------------------------------------------------------------
// Downscale

TEST(Downscale, AveragesBlocksWithRounding) {
    Image image = solid(4, 2, {0, 0, 0, 0});
    // Block (0,0): red 0, 10, 20, 31 -> 15.25 -> 15; green 1, 2, 2, 2 -> 1.75 -> 2; blue 0, 0, 1, 1 -> 0.5 -> 1.
    const std::uint8_t reds[4] = {0, 10, 20, 31}, greens[4] = {1, 2, 2, 2}, blues[4] = {0, 0, 1, 1};
    const int xs[4] = {0, 1, 0, 1}, ys[4] = {0, 0, 1, 1};
    for (int k = 0; k < 4; ++k) {
        const std::size_t i = 4 * (static_cast<std::size_t>(ys[k]) * 4 + xs[k]);
        image.rgba[i] = reds[k];
        image.rgba[i + 1] = greens[k];
        image.rgba[i + 2] = blues[k];
        image.rgba[i + 3] = 255;
    }
    const Image half = downscale(image, 2);
    ASSERT_EQ(half.width, 2);
    ASSERT_EQ(half.height, 1);
    EXPECT_EQ(pixel(half, 0, 0), (Rgba{15, 2, 1, 255}));
    EXPECT_EQ(pixel(half, 1, 0), (Rgba{0, 0, 0, 0}));
}

TEST(Downscale, PartialEdgeBlocksAverageWhatTheyHave) {
    Image image = solid(3, 3, {100, 100, 100, 255});
    image.rgba[4 * (2 * 3 + 2)] = 0;  // bottom-right pixel red 0: a 1x1 block of its own
    image.rgba[4 * (0 * 3 + 2)] = 50;  // top-right pixel: block of 1x2 with (2, 1)
    const Image out = downscale(image, 2);
    ASSERT_EQ(out.width, 2);
    ASSERT_EQ(out.height, 2);
    EXPECT_EQ(pixel(out, 0, 0), (Rgba{100, 100, 100, 255}));
    EXPECT_EQ(pixel(out, 1, 0), (Rgba{75, 100, 100, 255}));
    EXPECT_EQ(pixel(out, 0, 1), (Rgba{100, 100, 100, 255}));
    EXPECT_EQ(pixel(out, 1, 1), (Rgba{0, 100, 100, 255}));
}

TEST(Downscale, FactorOneCopiesAndLargeFactorsGiveOnePixel) {
    const Image image = pattern(5, 4);
    const Image same = downscale(image, 1);
    EXPECT_EQ(same.width, 5);
    EXPECT_EQ(same.height, 4);
    EXPECT_EQ(same.rgba, image.rgba);
    const Image one = downscale(solid(5, 4, {10, 20, 30, 40}), 1000000);
    ASSERT_EQ(one.width, 1);
    ASSERT_EQ(one.height, 1);
    EXPECT_EQ(pixel(one, 0, 0), (Rgba{10, 20, 30, 40}));
}

TEST(Downscale, InvalidArguments) {
    EXPECT_THROW(downscale(pattern(2, 2), 0), std::invalid_argument);
    EXPECT_THROW(downscale(pattern(2, 2), -2), std::invalid_argument);
    EXPECT_THROW(downscale(Image{}, 2), std::invalid_argument);
    Image bad = pattern(2, 2);
    bad.rgba.push_back(0);
    EXPECT_THROW(downscale(bad, 2), std::invalid_argument);
}

}  // namespace
}  // namespace cullide::io
