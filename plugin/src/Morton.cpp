#include "Morton.h"

#include "KeptCapacity.h"
#include "PoolOrHere.h"

#include <algorithm>
#include <array>

namespace cullide::morton {
namespace {

constexpr int kDigitBits = 10;
constexpr std::size_t kDigits = std::size_t{1} << kDigitBits;
constexpr std::size_t kChunk = 4096;  // keys per chunk of a pass

std::size_t digit(std::uint64_t key, int shift) { return static_cast<std::size_t>(key >> shift) & (kDigits - 1); }

}  // namespace

void sortByCode(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& tmp, std::vector<std::uint32_t>& counts,
                TaskPool* pool) {
    const std::size_t n = keys.size();
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    resizeKeeping(tmp, n);
    resizeKeeping(counts, chunks * kDigits);
    std::uint32_t* count = counts.data();  // digit-major: [d * chunks + c], so the prefix sum runs in order
    for (int shift = 32; shift < 62; shift += kDigitBits) {
        const std::uint64_t* from = keys.data();
        std::uint64_t* to = tmp.data();
        parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = begin; c < end; ++c) {
                std::array<std::uint32_t, kDigits> here{};
                for (std::size_t i = c * kChunk, last = std::min(n, i + kChunk); i < last; ++i)
                    ++here[digit(from[i], shift)];
                for (std::size_t d = 0; d < kDigits; ++d) count[d * chunks + c] = here[d];
            }
        });
        std::uint32_t sum = 0;
        for (std::size_t i = 0; i < kDigits * chunks; ++i) {
            const std::uint32_t here = count[i];
            count[i] = sum;  // from now on: where chunk c writes its first key with digit d
            sum += here;
        }
        parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = begin; c < end; ++c) {
                std::array<std::uint32_t, kDigits> cursor;
                for (std::size_t d = 0; d < kDigits; ++d) cursor[d] = count[d * chunks + c];
                for (std::size_t i = c * kChunk, last = std::min(n, i + kChunk); i < last; ++i)
                    to[cursor[digit(from[i], shift)]++] = from[i];
            }
        });
        keys.swap(tmp);
    }
}

}  // namespace cullide::morton
