// Waiting for another narrow-phase thread without spinning for long: on the shared 2-core machines a thread that
// spins (even yielding) takes the core from the thread it waits for as soon as a third process needs one.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>

namespace cullide::bullet {

/// Threads wait until a condition holds (a short spin, then asleep); the thread that changes what the condition reads
/// calls notify() after the change. The change must be a sequentially consistent atomic store (the default order):
/// either notify() sees the sleeper, or the sleeper sees the change.
class Waiter {
public:
    template <typename Ready>
    void wait(const Ready& ready) {
        for (int i = 0; i < kSpins; ++i)
            if (ready()) return;
        std::unique_lock<std::mutex> lock(m_mutex);
        m_sleepers.fetch_add(1);
        m_wake.wait(lock, ready);
        m_sleepers.fetch_sub(1);
    }
    void notify() {
        if (m_sleepers.load() == 0) return;
        std::lock_guard<std::mutex> lock(m_mutex);
        m_wake.notify_all();
    }

private:
    static constexpr int kSpins = 256;
    std::mutex m_mutex;
    std::condition_variable m_wake;
    std::atomic<int> m_sleepers{0};
};

}  // namespace cullide::bullet
