// What the process used: peak resident memory (VmHWM), and each thread's CPU time and allowed CPUs (to tell the
// culler's workers from threads a GL driver starts, and to see whether a driver narrowed the CPUs a thread may use).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace cullide::bench {

/// Peak resident set size of this process in KiB (VmHWM from /proc/self/status; getrusage as a fallback).
std::size_t peakResidentKb();

/// One thread of this process so far.
struct ThreadUse {
    std::string name;  ///< /proc/self/task/<tid>/comm (the culler's workers: TaskPool::kWorkerName)
    double cpuMs = 0.0;  ///< user + system time since the thread started
    std::string cpus;  ///< its Cpus_allowed_list ("0-15")
};

/// Every live thread of this process (Linux /proc; empty elsewhere), the most CPU time first.
std::vector<ThreadUse> threadUse();

/// Minor page faults of this process so far (getrusage). A frame that faults thousands of pages writes into freshly
/// allocated memory: milliseconds on a frame of a few.
long minorFaults();

/// The calling thread's Cpus_allowed_list (Linux; empty elsewhere).
std::string cpusAllowed();

}  // namespace cullide::bench
