#include "ReliableSettings.h"

namespace cullide::test {

Settings reliable(int resolution, Pipeline pipeline) {
    Settings s;
    s.resolution = resolution;
    s.pipeline = pipeline;
    s.exactThreshold = 0;              // run every GPU level in tests,
    s.gpuLevels = GpuLevels::Always;   // also on llvmpipe,
    s.deviceExact = DeviceExact::Always;  // and the device exact stage
    return s;
}

}  // namespace cullide::test
