// Morton (Z-order) codes of points in a box, and the stable radix sort that orders items by them in O(n): the
// spatial orders of whole meshes (TriangleOrders, kept between frames) and of the box trees' sorted leaves.
#pragma once

#include "cullide/TaskPool.h"

#include <cstdint>
#include <vector>

namespace cullide::morton {

/// Spreads the low 10 bits of v to every third bit.
inline std::uint32_t spreadBits(std::uint32_t v) {
    v &= 0x3FFu;
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

/// 30-bit code of a point whose coordinates are already scaled to [0, 1023]. Values outside are clamped, and a NaN
/// (overflow near the double range: inf * 0) counts as 0: the code only orders items, it never decides a pair.
inline std::uint32_t code(double x, double y, double z) {
    auto q = [](double v) { return !(v > 0.0) ? 0u : v >= 1023.0 ? 1023u : static_cast<std::uint32_t>(v); };
    return spreadBits(q(x)) | (spreadBits(q(y)) << 1) | (spreadBits(q(z)) << 2);
}

/// A sort key: the code in the high half, the item in the low half.
inline std::uint64_t key(std::uint32_t code, std::uint32_t item) {
    return (static_cast<std::uint64_t>(code) << 32) | item;
}

/// Stable LSD radix sort of keys by their code (bits 32..61), 10 bits a pass: items with equal codes keep their
/// input order. Each pass counts the digits of fixed chunks of keys, then each chunk scatters to its own run of each
/// digit's range; with `pool` the chunks of a pass run on its workers. The chunks do not depend on the number of
/// workers, so neither does the order. `tmp` and `counts` are working memory.
void sortByCode(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& tmp, std::vector<std::uint32_t>& counts,
                TaskPool* pool = nullptr);

}  // namespace cullide::morton
