// What one round trip to the GL device costs, measured on the device CULLIDE's GPU levels would use: the numbers that
// bound a frame of GPU levels from below (a chain of dependent dispatches, one blocking read-back).
#pragma once

#include <string>

namespace cullide {

/// measureGlLatency's figures, each the median over its repetitions, in microseconds.
struct GlLatency {
    std::string renderer;  ///< the renderer's name (as Stats::renderer)
    std::string device;    ///< the EGL device chosen (as Stats::device)
    int dispatches = 0;    ///< dependent dispatches timed as one batch
    int roundTrips = 0;    ///< repetitions of each round trip
    /// Device time per dependent dispatch (a one-invocation dispatch, a storage barrier, the next reading what it
    /// wrote), from a timer query over the batch; negative where the driver has no plausible timer result.
    double dispatchDeviceUs = -1.0;
    /// The calling thread's time to issue one dispatch and its barrier.
    double dispatchIssueUs = 0.0;
    /// A fence after one dispatch: inserted, then waited for (with a flush) until it signals.
    double fenceUs = 0.0;
    /// A blocking read-back of 4 bytes that the dispatch before it wrote.
    double readBackUs = 0.0;
};

/// Opens a GL context on `device` (as Settings::device: "" for CULLIDE_GL_DEVICE or automatic, "hardware",
/// "software", "surfaceless", an index) and measures it: `dispatches` dependent dispatches (at least 1) timed as a
/// batch, and `roundTrips` (at least 1) fences and read-backs; the dispatches' count is checked at every read-back.
/// Throws GlUnavailableError (cullide/Culler.h) where no usable GL device is there, std::invalid_argument for counts
/// below 1, std::runtime_error for a GL failure (a program that does not build, a fence that does not signal, a
/// count that is wrong). Uses a context of its own: afterwards no GL context is current on the calling thread.
GlLatency measureGlLatency(const std::string& device = "", int dispatches = 256, int roundTrips = 64);

}  // namespace cullide
