// What the process used: peak resident memory (VmHWM).
#pragma once

#include <cstddef>

namespace cullide::bench {

/// Peak resident set size of this process in KiB (VmHWM from /proc/self/status; getrusage as a fallback).
std::size_t peakResidentKb();

}  // namespace cullide::bench
