// The stages that take an optional pool: on its workers when there is one, on the calling thread otherwise.
#pragma once

#include "cullide/TaskPool.h"

#include <algorithm>
#include <cstddef>
#include <functional>

namespace cullide {

/// Calls fn(begin, end) over [0, count): on `pool`'s workers in chunks of `grain`, or once on this thread when
/// `pool` is null. The chunks are the caller's to make independent of the number of workers.
inline void parallelForOrHere(TaskPool* pool, std::size_t count, std::size_t grain,
                              const std::function<void(std::size_t, std::size_t)>& fn) {
    if (pool != nullptr)
        pool->parallelFor(count, grain, fn);
    else if (count > 0)
        fn(0, count);
}

/// Items per chunk for `total` items of about even cost: about kChunksPerWorker chunks for each of `pool`'s workers
/// (dynamic scheduling evens out the rest), but no fewer than `least` items (a chunk must outweigh its hand-off) and
/// no more than `most`. The result may depend on the pool's size: callers write per-index slots, so their output
/// does not.
inline std::size_t chunkFor(const TaskPool* pool, std::size_t total, std::size_t least, std::size_t most) {
    constexpr std::size_t kChunksPerWorker = 8;
    const std::size_t workers = pool != nullptr ? pool->size() : 1;
    return std::clamp(total / (kChunksPerWorker * workers), least, most);
}

}  // namespace cullide
