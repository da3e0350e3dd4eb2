// The GPU times of the visibility levels from timer queries (Stats::gpuMs, LevelStats::gpuMs): a result is taken only
// where it is available and plausible, and one absent result makes the level's and the frame's times absent.
#pragma once

#include "gl/GlApi.h"
#include "cullide/Stats.h"

namespace cullide::gl {

/// The GPU time of the span just timed by `query`, in ms, or -1 when it is not available or not plausible: the GPU
/// cannot have spent longer between glBeginQuery and glEndQuery than the CPU waited from issuing the first to holding
/// the result (`wallMs`, with 2% and 0.25 ms of slack for clock rates and timer granularity). llvmpipe (Mesa 22.3)
/// fails this once per context: its first TIME_ELAPSED result, with either back-end, is the end time stamp less a
/// start that was never stamped (0), i.e. CLOCK_MONOTONIC — the machine's uptime; its later results are plausible.
/// Call it after a read-back of the work timed: waiting for the result then costs next to nothing.
double timerResultMs(GLuint query, double wallMs);

/// Adds one span's GPU time (`ms` < 0: absent) to the level and the frame. One absent span makes the level's and the
/// frame's timings absent: a partial sum would read as a time.
void recordGpuTime(double ms, LevelStats& level, Stats& stats);

/// recordGpuTime for the span of the device exact stage that followed the level, also counted in its exactGpuMs.
void recordExactGpuTime(double ms, LevelStats& level, Stats& stats);

/// An upload's span (`ms` < 0: absent) into the frame's gpuMs and uploadGpuMs; absent, it makes the frame's timing
/// absent.
void recordUploadGpuTime(double ms, Stats& stats);

}  // namespace cullide::gl
