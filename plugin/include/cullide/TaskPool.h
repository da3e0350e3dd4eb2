// A small persistent worker pool (used by the culler's CPU stages and the Bullet adapter's narrow phase):
// parallelFor over an index range with dynamic chunking (chunks claimed with one atomic add; idle workers poll
// briefly before they sleep). Deterministic results are the caller's job (write to per-index slots).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
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
    /// How long an idle worker (and a caller waiting for the last chunks) keeps polling before it sleeps. A frame
    /// runs a few dozen parallelFor calls with short serial steps between them; waking a sleeping thread costs
    /// tens of microseconds each time, so workers stay awake across those steps, and sleep between frames. Only
    /// when the pool has no more threads than the process has CPUs; otherwise they sleep at once.
    static constexpr std::chrono::microseconds kSpin{100};

    /// `threads` = total workers including the calling thread; 0 = the CPUs this process may run on (its affinity
    /// mask where the platform has one, else the hardware concurrency).
    explicit TaskPool(unsigned threads);
    ~TaskPool();
    TaskPool(const TaskPool&) = delete;
    TaskPool& operator=(const TaskPool&) = delete;

    /// Calls fn(begin, end) on disjoint chunks covering [0, count); returns when all are done. Exceptions thrown
    /// by fn are rethrown on the calling thread (the first one). Not re-entrant: fn must not call parallelFor.
    void parallelFor(std::size_t count, std::size_t chunk, const std::function<void(std::size_t, std::size_t)>& fn);
    /// As parallelFor, but the calling thread first runs `first()` while the workers start on the chunks, then joins
    /// them (work that must stay on the calling thread, overlapped with the rest). An exception from `first` is
    /// rethrown once the chunks already started have finished.
    void parallelFor(std::size_t count, std::size_t chunk, const std::function<void(std::size_t, std::size_t)>& fn,
                     const std::function<void()>& first);
    unsigned size() const { return static_cast<unsigned>(m_workers.size()) + 1; }

private:
    struct Job;

    void workerLoop();
    bool waitForJob(std::uint64_t seen);
    void wakeWorkers(std::size_t wanted);
    void waitFinished(Job& job);

    std::vector<std::thread> m_workers;
    /// The running parallelFor's job (null between calls). Published before m_generation moves on; the caller
    /// returns only when no worker holds it any more (m_holders).
    std::atomic<Job*> m_job{nullptr};
    std::atomic<std::uint64_t> m_generation{0};
    std::atomic<unsigned> m_holders{0};   ///< workers that may be reading m_job's job
    std::atomic<unsigned> m_sleepers{0};  ///< workers asleep on m_wake
    std::atomic<bool> m_stop{false};
    bool m_spin = true;  ///< idle threads poll before they sleep (see kSpin)
    std::mutex m_mutex;  ///< only for sleeping and waking
    std::condition_variable m_wake;
    std::condition_variable m_done;
};

}  // namespace cullide
