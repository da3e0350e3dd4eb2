#include "ImageSupport.h"

#include <random>

namespace cullide::test {

Image pattern(int w, int h, std::uint32_t seed) {
    Image image;
    image.width = w;
    image.height = h;
    image.rgba.resize(4 * static_cast<std::size_t>(w) * h);
    std::mt19937 rng(seed);
    for (auto& b : image.rgba) b = static_cast<std::uint8_t>(rng());
    image.rgba[3] = 0;
    image.rgba[7 % image.rgba.size()] = 255;
    return image;
}

Image solid(int w, int h, std::array<std::uint8_t, 4> c) {
    Image image;
    image.width = w;
    image.height = h;
    for (int i = 0; i < w * h; ++i) image.rgba.insert(image.rgba.end(), c.begin(), c.end());
    return image;
}

std::array<std::uint8_t, 4> pixel(const Image& image, int x, int y) {
    const std::size_t i = 4 * (static_cast<std::size_t>(y) * image.width + x);
    return {image.rgba[i], image.rgba[i + 1], image.rgba[i + 2], image.rgba[i + 3]};
}

}  // namespace cullide::test
