// PNG files and simple image layout for snapshots (cullide::Image, rows top to bottom, RGBA8).
// Part of the cullide_io library (CMake: cullide::io; pkg-config: cullide-io), not of the culler.
#pragma once

#include "cullide/io/Snapshot.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace cullide::io {

/// Writes an 8-bit RGBA PNG. Throws std::invalid_argument for an invalid image (size < 1 or rgba.size() !=
/// 4 * width * height) and std::runtime_error naming the path and the reason when the file cannot be written.
void writePng(const std::string& path, const Image& image);

/// Reads any PNG libpng can convert to 8-bit RGBA (grey, grey + alpha, palette, RGB, RGBA; 1 to 16 bits;
/// interlaced or not; 16-bit channels are scaled, missing alpha is opaque; no gamma correction). Throws
/// std::runtime_error naming the path for a missing, unreadable, truncated or malformed file.
Image readPng(const std::string& path);

/// Tiles the images into a grid of `columns` columns (fewer when there are fewer images), row by row, with
/// `border` pixels of `borderColour` (opaque) around and between the cells. Every cell is as large as the largest
/// image; a smaller image sits at the centre of its cell (rounded toward the top left). Throws
/// std::invalid_argument for no images, an invalid image, columns < 1, a border outside 0..1024 or a sheet
/// larger than 65535 pixels in either direction.
Image makeContactSheet(const std::vector<Image>& images, int columns, int border = 4,
                       std::array<std::uint8_t, 3> borderColour = {128, 128, 128});

/// Box-filter reduction by an integer factor (thumbnails): the result is ceil(width / factor) x ceil(height /
/// factor); each output pixel is the rounded mean (halves up) of the input pixels of its block, all four channels,
/// blocks at the right and bottom edges averaging only the pixels they have. factor 1 copies. Throws
/// std::invalid_argument for an invalid image or factor < 1.
Image downscale(const Image& image, int factor);

}  // namespace cullide::io
