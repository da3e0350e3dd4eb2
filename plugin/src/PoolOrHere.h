// The stages that take an optional pool: on its workers when there is one, on the calling thread otherwise.
#pragma once

#include "cullide/TaskPool.h"

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

}  // namespace cullide
