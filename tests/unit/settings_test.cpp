// Settings validation (Settings::validate, no GL needed): the defaults are valid, every out-of-range field is
// rejected, and the paper's pipeline cannot run without GPU levels.
#include "Compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace cullide::test {
namespace {

TEST(Settings, DefaultsAreValid) { EXPECT_EQ(Settings{}.validate(), ""); }

TEST(Settings, RejectsOutOfRangeFields) {
    auto bad = [](auto mutate) {
        Settings s;
        mutate(s);
        return s.validate();
    };
    EXPECT_NE(bad([](Settings& s) { s.resolution = 8; }), "");
    EXPECT_NE(bad([](Settings& s) { s.resolution = 5000; }), "");
    EXPECT_NE(bad([](Settings& s) { s.groupSize = 0; }), "");
    EXPECT_NE(bad([](Settings& s) { s.maxIterations = 0; }), "");
    EXPECT_NE(bad([](Settings& s) { s.minPruneFraction = -0.01; }), "");
    EXPECT_NE(bad([](Settings& s) { s.minPruneFraction = 1.5; }), "");
    EXPECT_NE(bad([](Settings& s) { s.minPruneFraction = std::nan(""); }), "");
    EXPECT_EQ(bad([](Settings& s) { s.minPruneFraction = 0.0; }), "");
    EXPECT_EQ(bad([](Settings& s) { s.minPruneFraction = 1.0; }), "");
    EXPECT_NE(bad([](Settings& s) { s.margin = -1; }), "");
    EXPECT_NE(bad([](Settings& s) { s.margin = std::numeric_limits<double>::quiet_NaN(); }), "");
    EXPECT_NE(bad([](Settings& s) { s.margin = std::numeric_limits<double>::infinity(); }), "");
    EXPECT_NE(bad([](Settings& s) { s.deviceExact = static_cast<DeviceExact>(7); }), "");
    for (const char* device : {"bogus", "gpu", "-1", "1.5", " 0", "12345", "00", "07"})
        EXPECT_NE(bad([device](Settings& s) { s.device = device; }), "") << device;
    for (const char* device : {"", "hardware", "software", "surfaceless", "0", "99", "1234"})
        EXPECT_EQ(bad([device](Settings& s) { s.device = device; }), "") << device;
    Settings s;
    s.resolution = 1;
    EXPECT_THROW(createReferenceCuller(s), std::invalid_argument);
    EXPECT_THROW(createGpuCuller(s), std::invalid_argument);
}

TEST(Settings, PaperWithNeverIsRejected) {
    Settings s;
    s.pipeline = Pipeline::Paper;
    s.gpuLevels = GpuLevels::Never;
    const std::string error = s.validate();
    EXPECT_NE(error.find("Paper"), std::string::npos) << error;
    EXPECT_NE(error.find("Never"), std::string::npos) << error;
    EXPECT_THROW(createGpuCuller(s), std::invalid_argument);
    for (GpuLevels levels : {GpuLevels::Auto, GpuLevels::Always}) {
        s.gpuLevels = levels;
        EXPECT_EQ(s.validate(), "");
    }
    s.pipeline = Pipeline::Auto;
    s.gpuLevels = GpuLevels::Never;
    EXPECT_EQ(s.validate(), "");
}

}  // namespace
}  // namespace cullide::test
