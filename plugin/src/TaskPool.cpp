#include "cullide/TaskPool.h"

#include <algorithm>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif
#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#endif

namespace cullide {
namespace {

/// Workers are named (Linux: top -H, perf, /proc/<pid>/task/*/comm) so that a profile or a thread listing tells the
/// culler's workers from the application's and a GL driver's threads.
void nameWorkerThread() {
#if defined(__linux__)
    pthread_setname_np(pthread_self(), TaskPool::kWorkerName);
#endif
}

/// The CPUs this process may run on (its affinity mask on Linux: a container or `taskset` may allow fewer than the
/// machine has), at least 1.
unsigned allowedCpus() {
#if defined(__linux__)
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
#endif
    return std::max(1u, std::thread::hardware_concurrency());
}

/// Polls `ready` for up to TaskPool::kSpin, or kBusySpin while a Busy scope is open (`busy` non-zero: read on
/// every round, so a poll begun in a frame ends soon after the frame does): a few pause instructions between reads,
/// the rest of the time slice handed back between rounds (a machine with more threads than cores, or a GL driver's
/// threads, still run).
template <typename Ready>
bool pollFor(bool spin, const std::atomic<unsigned>& busy, const Ready& ready) {
    if (!spin) return ready();
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
        for (int i = 0; i < 64; ++i) {
            if (ready()) return true;
#if defined(__SSE2__) || defined(_M_X64)
            _mm_pause();
#endif
        }
        const auto limit = busy.load(std::memory_order_relaxed) != 0 ? TaskPool::kBusySpin : TaskPool::kSpin;
        if (std::chrono::steady_clock::now() - start >= limit) return ready();
        std::this_thread::yield();
    }
}

}  // namespace

/// One parallelFor call, on the caller's stack. Chunks are claimed by an atomic add on `next`; `finished` counts
/// the indices done (or dropped after an error), so the caller knows when the last chunk is over.
struct TaskPool::Job {
    const std::function<void(std::size_t, std::size_t)>& fn;
    const std::size_t count;
    const std::size_t chunk;
    std::atomic<std::size_t> next{0};
    std::atomic<std::size_t> finished{0};
    std::atomic<bool> failed{false};     ///< chunks not started yet are dropped
    std::atomic<bool> callerAsleep{false};
    std::mutex errorMutex;
    std::exception_ptr error;

    Job(const std::function<void(std::size_t, std::size_t)>& f, std::size_t n, std::size_t c)
        : fn(f), count(n), chunk(c) {}

    void fail(std::exception_ptr e) {
        const std::lock_guard<std::mutex> lock(errorMutex);
        if (!error) error = std::move(e);
        failed.store(true);
    }

    /// Runs chunks until none is left. Returns true when this thread finished the job's last index.
    bool runChunks() {
        bool last = false;
        for (;;) {
            const std::size_t begin = next.fetch_add(chunk);
            if (begin >= count) return last;
            const std::size_t end = std::min(count, begin + chunk);
            if (!failed.load(std::memory_order_relaxed)) {
                try {
                    fn(begin, end);
                } catch (...) {
                    fail(std::current_exception());
                }
            }
            last = finished.fetch_add(end - begin) + (end - begin) == count;
        }
    }

    bool done() const { return finished.load() == count; }
};

TaskPool::TaskPool(unsigned threads) {
    const unsigned cpus = allowedCpus();
    const unsigned n = threads != 0 ? threads : cpus;
    // Polling pays only when every thread has a CPU of its own: with more threads than CPUs, a polling worker takes
    // time slices from the ones that work (measured: the chunks of 16 threads on 2 CPUs ran at half speed).
    m_spin = n <= cpus;
    for (unsigned i = 1; i < n; ++i) m_workers.emplace_back([this] {
            nameWorkerThread();
            workerLoop();
        });
}

TaskPool::~TaskPool() {
    {
        std::lock_guard<std::mutex> lock(m_mutex);
        m_stop.store(true);
    }
    m_wake.notify_all();
    for (auto& t : m_workers) t.join();
}

bool TaskPool::waitForJob(std::uint64_t seen) {
    auto ready = [&] { return m_stop.load() || m_generation.load() != seen; };
    while (!pollFor(m_spin, m_busy, ready)) {
        std::unique_lock<std::mutex> lock(m_mutex);
        const std::uint64_t nudges = m_nudges.load();
        m_sleepers.fetch_add(1);  // before the predicate's check: a caller that misses it sees a sleeper
        m_wake.wait(lock, [&] { return ready() || m_nudges.load() != nudges; });
        m_sleepers.fetch_sub(1);
        const bool nudged = m_nudges.load() != nudges;  // a Busy scope started this wake-up ahead of the job
        if (ready()) {
            if (!nudged) m_workerWakes.fetch_add(1, std::memory_order_relaxed);
            break;
        }
        // Woken by a Busy scope: poll again, for its longer time.
    }
    return !m_stop.load();
}

void TaskPool::workerLoop() {
    std::uint64_t seen = 0;
    while (waitForJob(seen)) {
        seen = m_generation.load();
        // Holding first, then reading the job: a caller that has cleared m_job and then sees no holder knows that
        // no worker can still reach its job (all sequentially consistent).
        m_holders.fetch_add(1);
        Job* job = m_job.load();
        if (job != nullptr && job->runChunks() && job->callerAsleep.load()) {
            const std::lock_guard<std::mutex> lock(m_mutex);
            m_done.notify_all();
        }
        m_holders.fetch_sub(1);
    }
}

TaskPool::Counters TaskPool::counters() const {
    Counters c;
    c.calls = m_calls.load(std::memory_order_relaxed);
    c.workerWakes = m_workerWakes.load(std::memory_order_relaxed);
    c.callerSleeps = m_callerSleeps.load(std::memory_order_relaxed);
    return c;
}

TaskPool::Busy::Busy(TaskPool& pool) : m_pool(pool) {
    if (m_pool.m_busy.fetch_add(1) != 0 || !m_pool.m_spin || m_pool.m_sleepers.load() == 0) return;
    {
        const std::lock_guard<std::mutex> lock(m_pool.m_mutex);  // a worker between its check and its wait waits now
        m_pool.m_nudges.fetch_add(1);
    }
    m_pool.m_wake.notify_all();
}

TaskPool::Busy::~Busy() { m_pool.m_busy.fetch_sub(1); }

void TaskPool::wakeWorkers(std::size_t wanted) {
    const unsigned sleepers = m_sleepers.load();
    if (sleepers == 0) return;
    const std::lock_guard<std::mutex> lock(m_mutex);  // a worker between its check and its wait is waiting now
    for (std::size_t i = 0; i < std::min<std::size_t>(wanted, sleepers); ++i) m_wake.notify_one();
}

void TaskPool::waitFinished(Job& job) {
    if (pollFor(m_spin, m_busy, [&] { return job.done(); })) return;
    std::unique_lock<std::mutex> lock(m_mutex);
    m_callerSleeps.fetch_add(1, std::memory_order_relaxed);
    job.callerAsleep.store(true);  // before the predicate's check: the worker that ends the job then notifies
    m_done.wait(lock, [&] { return job.done(); });
}

void TaskPool::parallelFor(std::size_t count, std::size_t chunk,
                           const std::function<void(std::size_t, std::size_t)>& fn) {
    parallelFor(count, chunk, fn, {});
}

void TaskPool::parallelFor(std::size_t count, std::size_t chunk,
                           const std::function<void(std::size_t, std::size_t)>& fn,
                           const std::function<void()>& first) {
    if (m_workers.empty() || count <= chunk) {
        if (first) first();
        if (count > 0) fn(0, count);
        return;
    }
    m_calls.fetch_add(1, std::memory_order_relaxed);
    Job job(fn, count, std::max<std::size_t>(1, chunk));
    m_job.store(&job);
    m_generation.fetch_add(1);
    wakeWorkers((count + job.chunk - 1) / job.chunk);
    if (first) {
        try {
            first();
        } catch (...) {
            job.fail(std::current_exception());
        }
    }
    job.runChunks();
    waitFinished(job);
    m_job.store(nullptr);
    while (m_holders.load() != 0) std::this_thread::yield();  // a worker may still be reading `job`
    if (job.error) std::rethrow_exception(job.error);
}

}  // namespace cullide
