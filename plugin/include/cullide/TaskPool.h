// A small persistent worker pool (used by the culler's CPU stages and the Bullet adapter's narrow phase):
// parallelFor over an index range with dynamic chunking. Deterministic results are the caller's job (write to
// per-index slots).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace cullide {

class TaskPool {
public:
    /// The name each worker thread gets where the platform has thread names (Linux: 15 characters at most).
    static constexpr const char* kWorkerName = "cullide-worker";

    /// `threads` = total workers including the calling thread; 0 = hardware concurrency.
    explicit TaskPool(unsigned threads);
    ~TaskPool();
    TaskPool(const TaskPool&) = delete;
    TaskPool& operator=(const TaskPool&) = delete;

    /// Calls fn(begin, end) on disjoint chunks covering [0, count); returns when all are done. Exceptions thrown
    /// by fn are rethrown on the calling thread (the first one).
    void parallelFor(std::size_t count, std::size_t chunk, const std::function<void(std::size_t, std::size_t)>& fn);
    /// As parallelFor, but the calling thread first runs `first()` while the workers start on the chunks, then joins
    /// them (work that must stay on the calling thread, overlapped with the rest). An exception from `first` is
    /// rethrown once the chunks already started have finished.
    void parallelFor(std::size_t count, std::size_t chunk, const std::function<void(std::size_t, std::size_t)>& fn,
                     const std::function<void()>& first);
    unsigned size() const { return static_cast<unsigned>(m_workers.size()) + 1; }

private:
    void workerLoop();
    void drain(std::unique_lock<std::mutex>& lock);

    std::vector<std::thread> m_workers;
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::condition_variable m_done;
    const std::function<void(std::size_t, std::size_t)>* m_fn = nullptr;
    std::size_t m_count = 0;
    std::size_t m_chunk = 1;
    std::size_t m_next = 0;
    std::size_t m_busy = 0;
    std::size_t m_generation = 0;
    bool m_stop = false;
    std::exception_ptr m_error;
};

}  // namespace cullide
