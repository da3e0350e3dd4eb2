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
    /// How long an idle worker (and a caller waiting for the last chunks) keeps polling before it sleeps, outside
    /// a Busy scope: back-to-back calls find the workers awake, and they sleep soon between frames (where the
    /// application's own threads, or the Bullet adapter's narrow-phase pool, want the cores). Polling happens only
    /// when the pool has no more threads than the process has CPUs; otherwise they sleep at once.
    static constexpr std::chrono::microseconds kSpin{100};
    /// The same, while a Busy scope is open (a culler frame: a few dozen parallelFor calls with serial steps between
    /// them). A wake-up costs a futex call and, on a virtual machine, an interrupt to a halted virtual CPU (tens to
    /// hundreds of microseconds, on a loop's critical path), so within a frame threads poll through its serial
    /// steps. Checked on every round of polling: when the scope closes, polls fall back to kSpin.
    static constexpr std::chrono::microseconds kBusySpin{2000};

    /// What the pool's threads did since it was made (Stats reports them per frame).
    struct Counters {
        std::uint64_t calls = 0;         ///< parallelFor calls handed to the workers (not run on the caller alone)
        std::uint64_t workerWakes = 0;  ///< times a parallelFor woke a sleeping worker (not a Busy scope's wake-up)
        std::uint64_t callerSleeps = 0;  ///< times a caller slept waiting for the workers' last chunks
    };

    /// While one exists, threads poll for kBusySpin instead of kSpin, and its constructor wakes the sleeping
    /// workers, so that their wake-ups overlap the caller's serial work before its first parallelFor. For a span of
    /// many parallelFor calls with short serial steps between them (one culler frame). Scopes may nest; open and
    /// close them on the thread that calls parallelFor.
    class Busy {
    public:
        explicit Busy(TaskPool& pool);
        ~Busy();
        Busy(const Busy&) = delete;
        Busy& operator=(const Busy&) = delete;

    private:
        TaskPool& m_pool;
    };

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
    Counters counters() const;

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
    std::atomic<unsigned> m_busy{0};  ///< open Busy scopes
    std::atomic<std::uint64_t> m_nudges{0};  ///< moved on (under m_mutex) to wake sleeping workers without a job
    std::atomic<std::uint64_t> m_calls{0};
    std::atomic<std::uint64_t> m_workerWakes{0};
    std::atomic<std::uint64_t> m_callerSleeps{0};
    std::mutex m_mutex;  ///< only for sleeping and waking
    std::condition_variable m_wake;
    std::condition_variable m_done;
};

}  // namespace cullide
