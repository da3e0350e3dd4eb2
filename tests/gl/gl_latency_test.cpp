// measureGlLatency (cullide/GlLatency.h): what a dependent dispatch, a fence and a blocking read-back cost on the GL
// device, the floor under a frame of GPU levels (cullide-bench-run --probe prints it).
#include "GlTestSupport.h"
#include "cullide/GlLatency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace cullide::test {
namespace {

TEST(GlLatency, MeasuresEachRoundTripOnTheDevice) {
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);  // a usable GL device, or skip (fail with CI=true)
    const GlLatency l = measureGlLatency(settings.device, 16, 8);
    EXPECT_FALSE(l.renderer.empty());
    EXPECT_FALSE(l.device.empty());
    EXPECT_EQ(l.dispatches, 16);
    EXPECT_EQ(l.roundTrips, 8);
    // Each is a time the calling thread spent: positive and finite (a clock reads at least a tick of the call).
    for (double us : {l.dispatchIssueUs, l.fenceUs, l.readBackUs}) {
        EXPECT_TRUE(std::isfinite(us));
        EXPECT_GT(us, 0.0);
        EXPECT_LT(us, 1e7);
    }
    EXPECT_TRUE(l.dispatchDeviceUs < 0.0 || std::isfinite(l.dispatchDeviceUs)) << l.dispatchDeviceUs;
}

TEST(GlLatency, CountsBelowOneAreRejected) {
    EXPECT_THROW(measureGlLatency("", 0, 8), std::invalid_argument);
    EXPECT_THROW(measureGlLatency("", 8, 0), std::invalid_argument);
}

}  // namespace
}  // namespace cullide::test
