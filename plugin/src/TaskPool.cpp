#include "cullide/TaskPool.h"

#include <algorithm>

#if defined(__linux__)
#include <pthread.h>
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

}  // namespace

TaskPool::TaskPool(unsigned threads) {
    unsigned n = threads != 0 ? threads : std::max(1u, std::thread::hardware_concurrency());
    for (unsigned i = 1; i < n; ++i) m_workers.emplace_back([this] {
            nameWorkerThread();
            workerLoop();
        });
}

TaskPool::~TaskPool() {
    {
        std::lock_guard<std::mutex> lock(m_mutex);
        m_stop = true;
    }
    m_wake.notify_all();
    for (auto& t : m_workers) t.join();
}

void TaskPool::drain(std::unique_lock<std::mutex>& lock) {
    while (m_fn != nullptr && m_next < m_count) {
        const std::size_t begin = m_next;
        const std::size_t end = std::min(m_count, begin + m_chunk);
        m_next = end;
        ++m_busy;
        const auto* fn = m_fn;
        lock.unlock();
        std::exception_ptr error;
        try {
            (*fn)(begin, end);
        } catch (...) {
            error = std::current_exception();
        }
        lock.lock();
        if (error) {
            if (!m_error) m_error = error;
            m_next = m_count;
        }
        if (--m_busy == 0 && m_next >= m_count) m_done.notify_all();
    }
}

void TaskPool::workerLoop() {
    std::unique_lock<std::mutex> lock(m_mutex);
    std::size_t seen = 0;
    for (;;) {
        m_wake.wait(lock, [&] { return m_stop || (m_generation != seen && m_fn != nullptr && m_next < m_count); });
        if (m_stop) return;
        seen = m_generation;
        drain(lock);
    }
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
    std::unique_lock<std::mutex> lock(m_mutex);
    m_fn = &fn;
    m_count = count;
    m_chunk = std::max<std::size_t>(1, chunk);
    m_next = 0;
    m_error = nullptr;
    ++m_generation;
    m_wake.notify_all();
    if (first) {
        lock.unlock();
        std::exception_ptr error;
        try {
            first();
        } catch (...) {
            error = std::current_exception();
        }
        lock.lock();
        if (error) {
            if (!m_error) m_error = error;
            m_next = m_count;  // the chunks not started yet are dropped
        }
    }
    drain(lock);
    m_done.wait(lock, [&] { return m_busy == 0 && m_next >= m_count; });
    m_fn = nullptr;
    if (m_error) std::rethrow_exception(m_error);
}

}  // namespace cullide
