#include "gl/GpuTimes.h"

#include <cmath>

namespace cullide::gl {
namespace {

/// A timer-query result is plausible when at most this factor times the CPU wall time of the same span plus this
/// slack (clock-rate differences, timer granularity).
constexpr double kTimerFactor = 1.02;
constexpr double kTimerSlackMs = 0.25;

}  // namespace

double timerResultMs(GLuint query, double wallMs) {
    // A driver that still says the result is not available has no trustworthy result.
    GLuint64 ns = 0;
    glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
    GLint available = GL_FALSE;
    glGetQueryObjectiv(query, GL_QUERY_RESULT_AVAILABLE, &available);
    const double ms = static_cast<double>(ns) * 1e-6;
    if (available != GL_TRUE || !std::isfinite(ms) || ms > kTimerFactor * wallMs + kTimerSlackMs) return -1.0;
    return ms;
}

void recordUploadGpuTime(double ms, Stats& stats) {
    if (ms < 0.0) {
        stats.gpuTimingValid = false;
        stats.gpuMs = 0.0;
        stats.uploadGpuMs = 0.0;
        return;
    }
    if (!stats.gpuTimingValid) return;
    stats.gpuMs += ms;
    stats.uploadGpuMs += ms;
}

void recordGpuTime(double ms, LevelStats& level, Stats& stats) {
    if (ms < 0.0) {
        level.gpuTimingValid = false;
        level.gpuMs = 0.0;
        level.exactGpuMs = 0.0;
        recordUploadGpuTime(ms, stats);  // the frame's time absent too
        return;
    }
    if (level.gpuTimingValid) level.gpuMs += ms;
    if (stats.gpuTimingValid) stats.gpuMs += ms;
}

void recordExactGpuTime(double ms, LevelStats& level, Stats& stats) {
    recordGpuTime(ms, level, stats);
    if (level.gpuTimingValid) level.exactGpuMs += ms;
}

}  // namespace cullide::gl
