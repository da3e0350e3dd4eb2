// Fork/join cost of cullide::TaskPool, the pool every CPU stage of the culler runs on (a frame makes a few dozen
// parallelFor calls). For 1, 2, 4, ... threads up to --threads (default: the CPUs this process may use) and two
// chunk sizes, it times `--calls` calls of 4 chunks per thread, with `--gap-us` of serial work between calls (the
// steps of a frame between its parallel loops), and prints per call the median and 90th percentile against the
// ideal: the same chunks on one thread, divided by the threads. The difference is what a call costs beyond its work.
//   cullide-pool-bench [--threads N] [--calls N] [--gap-us N]
#include "cullide/TaskPool.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double usSince(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

std::atomic<std::uint64_t> g_sink{0};

/// Work the compiler cannot drop: `steps` dependent integer steps.
void spinWork(std::uint64_t seed, int steps) {
    std::uint64_t x = seed | 1u;
    for (int i = 0; i < steps; ++i) x = x * 6364136223846793005ull + 1442695040888963407ull;
    g_sink.fetch_add(x, std::memory_order_relaxed);
}

/// The pool's own default: the CPUs this process may use.
unsigned allowedCpus() { return cullide::TaskPool(0).size(); }

struct Options {
    unsigned threads = allowedCpus();
    int calls = 2000;
    int gapUs = 20;
};

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (i + 1 >= argc) throw std::invalid_argument("missing value after " + arg);
        const long value = std::strtol(argv[++i], nullptr, 10);
        if (value < 1 || value > 100000) throw std::invalid_argument("out of range: " + arg);
        if (arg == "--threads")
            o.threads = static_cast<unsigned>(value);
        else if (arg == "--calls")
            o.calls = static_cast<int>(value);
        else if (arg == "--gap-us")
            o.gapUs = static_cast<int>(value);
        else
            throw std::invalid_argument("unknown option " + arg);
    }
    return o;
}

/// Median microseconds of running `chunks` chunks of `steps` on this thread.
double serialUs(std::size_t chunks, int steps) {
    std::vector<double> samples;
    for (int rep = 0; rep < 200; ++rep) {
        const auto t0 = Clock::now();
        for (std::size_t c = 0; c < chunks; ++c) spinWork(c, steps);
        samples.push_back(usSince(t0));
    }
    std::sort(samples.begin(), samples.end());
    return samples[samples.size() / 2];
}

void measure(unsigned threads, int steps, const Options& o) {
    cullide::TaskPool pool(threads);
    const std::size_t chunks = 4u * threads;
    const double ideal = serialUs(chunks, steps) / threads;
    std::vector<double> samples;
    for (int call = 0; call < o.calls; ++call) {
        const auto t0 = Clock::now();
        pool.parallelFor(chunks, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t c = begin; c < end; ++c) spinWork(c, steps);
        });
        samples.push_back(usSince(t0));
        const auto gap = Clock::now();
        while (usSince(gap) < o.gapUs) spinWork(0, 16);
    }
    std::sort(samples.begin(), samples.end());
    const double median = samples[samples.size() / 2];
    std::printf("threads %2u  chunk %6.2f us  per call: median %8.2f us  p90 %8.2f us  ideal %8.2f us  "
                "overhead %7.2f us\n",
                threads, ideal * threads / static_cast<double>(chunks), median, samples[samples.size() * 9 / 10], ideal,
                median - ideal);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const Options o = parse(argc, argv);
        std::printf("cullide-pool-bench: %d calls per row, %d us of serial work between calls, %u CPUs allowed\n",
                    o.calls, o.gapUs, allowedCpus());
        std::vector<unsigned> counts;  // 1, 2, 4, ... and the largest
        for (unsigned n = 1; n < o.threads; n *= 2) counts.push_back(n);
        counts.push_back(o.threads);
        for (const int steps : {500, 5000})
            for (const unsigned threads : counts) measure(threads, steps, o);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide-pool-bench: %s\n", e.what());
        return 2;
    }
    return 0;
}
