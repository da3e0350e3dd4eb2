// Images (cullide::Image) with known pixels and pixel access: what the PNG, contact-sheet and downscale tests share.
#pragma once

#include "cullide/io/Image.h"

#include <array>
#include <cstdint>

namespace cullide::test {

using Rgba = std::array<std::uint8_t, 4>;

/// A w x h image whose every byte differs from its neighbours (alpha too, including 0 and 255).
Image pattern(int w, int h, std::uint32_t seed = 1);

/// A w x h image of colour c.
Image solid(int w, int h, std::array<std::uint8_t, 4> c);

/// The RGBA bytes of pixel (x, y).
std::array<std::uint8_t, 4> pixel(const Image& image, int x, int y);

}  // namespace cullide::test
