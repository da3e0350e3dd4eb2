// TaskPool: every index once, on any thread count and whether the workers are awake or asleep; the caller-first
// variant runs its own work on the calling thread while the workers start, and hands back exceptions from either
// side; idle workers sleep.
#include "cullide/TaskPool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#include <time.h>
#endif

namespace cullide {
namespace {

TEST(TaskPool, EveryIndexOnceForEveryThreadCount) {
    for (const unsigned threads : {1u, 2u, 5u}) {
        TaskPool pool(threads);
        for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{1000}}) {
            std::vector<std::atomic<int>> hits(997);
            pool.parallelFor(hits.size(), chunk, [&](std::size_t begin, std::size_t end) {
                for (std::size_t i = begin; i < end; ++i) hits[i].fetch_add(1);
            });
            for (const auto& h : hits) ASSERT_EQ(h.load(), 1) << threads << " threads, chunk " << chunk;
        }
    }
}

TEST(TaskPool, FirstRunsOnTheCallingThreadWhileWorkersTakeTheChunks) {
    for (const unsigned threads : {1u, 2u, 5u}) {
        TaskPool pool(threads);
        const std::thread::id caller = std::this_thread::get_id();
        std::atomic<std::thread::id> firstOn{};
        std::atomic<bool> release{false};
        std::atomic<int> done{0};
        std::atomic<int> onWorkers{0};
        // With workers, `first` waits until a worker has finished a chunk: it must not run before them.
        pool.parallelFor(
            64, 1,
            [&](std::size_t begin, std::size_t end) {
                if (std::this_thread::get_id() != caller) onWorkers.fetch_add(1);
                done.fetch_add(static_cast<int>(end - begin));
                release.store(true);
            },
            [&] {
                firstOn.store(std::this_thread::get_id());
                while (threads > 1 && !release.load()) std::this_thread::yield();
            });
        EXPECT_EQ(firstOn.load(), caller);
        EXPECT_EQ(done.load(), 64);
        if (threads > 1) {
            EXPECT_GT(onWorkers.load(), 0);
        }
    }
}

TEST(TaskPool, ExceptionsFromEitherSideReachTheCaller) {
    TaskPool pool(3);
    std::atomic<int> chunks{0};
    EXPECT_THROW(pool.parallelFor(
                     100, 1, [&](std::size_t, std::size_t) { chunks.fetch_add(1); },
                     [] { throw std::runtime_error("first"); }),
                 std::runtime_error);
    EXPECT_THROW(pool.parallelFor(
                     100, 1,
                     [](std::size_t begin, std::size_t) {
                         if (begin == 50) throw std::logic_error("chunk");
                     },
                     [] {}),
                 std::logic_error);
    // The pool is usable afterwards.
    std::atomic<int> n{0};
    pool.parallelFor(10, 1, [&](std::size_t, std::size_t) { n.fetch_add(1); }, [] {});
    EXPECT_EQ(n.load(), 10);
}

TEST(TaskPool, BackToBackAndAfterSleepingEveryIndexOnce) {
    // Workers poll for a while after a call (the next one finds them awake) and then sleep (the next one wakes
    // them): both hand-overs, with counts below, at and above the number of chunks, on several pool sizes.
    for (const unsigned threads : {2u, 4u, 9u}) {
        TaskPool pool(threads);
        for (int call = 0; call < 400; ++call) {
            const std::size_t count = static_cast<std::size_t>(call % 37) * 3 + 1;
            std::vector<std::atomic<int>> hits(count);
            pool.parallelFor(count, 1 + static_cast<std::size_t>(call % 3), [&](std::size_t begin, std::size_t end) {
                for (std::size_t i = begin; i < end; ++i) hits[i].fetch_add(1);
            });
            for (const auto& h : hits) ASSERT_EQ(h.load(), 1) << threads << " threads, call " << call;
            if (call % 50 == 49) std::this_thread::sleep_for(TaskPool::kSpin * 20);  // every worker asleep
        }
    }
}

TEST(TaskPool, CountsOnlyTheCallsHandedToTheWorkers) {
    TaskPool pool(3);
    const std::uint64_t before = pool.counters().calls;
    pool.parallelFor(5, 10, [](std::size_t, std::size_t) {});  // one chunk: the caller alone
    pool.parallelFor(0, 1, [](std::size_t, std::size_t) {});
    EXPECT_EQ(pool.counters().calls, before);
    pool.parallelFor(64, 1, [](std::size_t, std::size_t) {});
    EXPECT_EQ(pool.counters().calls, before + 1);
    TaskPool alone(1);
    alone.parallelFor(64, 1, [](std::size_t, std::size_t) {});
    EXPECT_EQ(alone.counters().calls, 0u);
}

#if defined(__linux__)
/// The CPUs this process may run on (a pool polls only when it has no more threads than that).
unsigned allowedCpus() {
    cpu_set_t set;
    CPU_ZERO(&set);
    return sched_getaffinity(0, sizeof set, &set) == 0 ? static_cast<unsigned>(CPU_COUNT(&set)) : 1u;
}

TEST(TaskPool, ABusyScopeWakesTheWorkersAheadOfItsLoops) {
    // A loop that finds its workers asleep waits for their wake-ups (counted); a Busy scope wakes them when it
    // opens, while the caller does its serial work, so its loops find them polling.
    if (allowedCpus() < 2) GTEST_SKIP() << "one CPU: a pool of two threads does not poll";
    TaskPool pool(2);
    auto wakesOver = [&](bool busy) {
        const std::uint64_t before = pool.counters().workerWakes;
        for (int i = 0; i < 5; ++i) {
            std::this_thread::sleep_for(TaskPool::kSpin * 100);  // every worker asleep, even on a loaded machine
            std::optional<TaskPool::Busy> scope;
            if (busy) scope.emplace(pool);
            std::this_thread::sleep_for(TaskPool::kSpin * 2);  // the caller's serial work
            pool.parallelFor(4, 1, [](std::size_t, std::size_t) {
                std::this_thread::sleep_for(std::chrono::microseconds(500));
            });
        }
        std::this_thread::sleep_for(TaskPool::kSpin * 20);  // a late wake-up is counted too
        return pool.counters().workerWakes - before;
    };
    // A loaded machine may keep a thread off its CPU for longer than these sleeps: a few attempts each.
    std::uint64_t without = 0, with = 1;
    for (int attempt = 0; attempt < 4 && without < 3; ++attempt) without = wakesOver(false);
    for (int attempt = 0; attempt < 4 && with != 0; ++attempt) with = wakesOver(true);
    EXPECT_GE(without, 3u);
    EXPECT_EQ(with, 0u);
}

TEST(TaskPool, IdleWorkersSleep) {
    // Polling is bounded: a pool between frames must not keep cores busy. Two threads: no more than the CPUs of
    // any test machine, so the worker polls after the call (a larger pool on a small machine sleeps at once).
    TaskPool pool(2);
    std::atomic<int> n{0};
    pool.parallelFor(64, 1, [&](std::size_t, std::size_t) { n.fetch_add(1); });
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    auto processCpuMs = [] {
        timespec t{};
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
        return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
    };
    const double before = processCpuMs();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    // A worker polling all along would use 200 ms of CPU time.
    EXPECT_LT(processCpuMs() - before, 40.0);
    EXPECT_EQ(n.load(), 64);
}

TEST(TaskPool, CallerWaitingForALongChunkSleeps) {
    // Whichever chunk the caller takes, it must not burn its core while a worker finishes a long one.
    TaskPool pool(2);
    auto threadCpuMs = [] {
        timespec t{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
        return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
    };
    const std::thread::id caller = std::this_thread::get_id();
    for (int attempt = 0; attempt < 20; ++attempt) {
        std::atomic<bool> callerTookTheShortOne{false};
        const double before = threadCpuMs();
        const std::uint64_t sleepsBefore = pool.counters().callerSleeps;
        std::atomic<bool> workerTookTheLongOne{false};
        pool.parallelFor(2, 1, [&](std::size_t begin, std::size_t) {
            // The first chunk claimed is short, the second long: the caller usually claims first.
            const bool shortOne = begin == 0;
            if (shortOne && std::this_thread::get_id() == caller) callerTookTheShortOne.store(true);
            if (!shortOne && std::this_thread::get_id() != caller) workerTookTheLongOne.store(true);
            std::this_thread::sleep_for(std::chrono::milliseconds(shortOne ? 1 : 150));
        });
        const double used = threadCpuMs() - before;
        if (!callerTookTheShortOne.load() || !workerTookTheLongOne.load()) continue;
        EXPECT_LT(used, 50.0);  // polling all along would be ~150 ms
        EXPECT_EQ(pool.counters().callerSleeps, sleepsBefore + 1);
        return;
    }
    GTEST_SKIP() << "the caller never took the short chunk while a worker took the long one";
}
#endif

#if defined(__linux__)
TEST(TaskPool, WorkersCarryTheirName) {
    // A thread listing (top -H, perf, /proc) must tell the culler's workers from a GL driver's threads.
    TaskPool pool(3);
    const std::thread::id caller = std::this_thread::get_id();
    std::mutex mutex;
    std::set<std::string> names;
    for (int attempt = 0; attempt < 200 && names.empty(); ++attempt) {
        pool.parallelFor(16, 1, [&](std::size_t, std::size_t) {
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
            if (std::this_thread::get_id() == caller) return;
            char name[16] = {};
            ASSERT_EQ(pthread_getname_np(pthread_self(), name, sizeof name), 0);
            const std::lock_guard<std::mutex> lock(mutex);
            names.insert(name);
        });
    }
    EXPECT_EQ(names, std::set<std::string>{TaskPool::kWorkerName});
}
#endif

}  // namespace
}  // namespace cullide
