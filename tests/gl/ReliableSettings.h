// Settings that run every GPU level in reliable mode, also on llvmpipe (the GPU culler tests).
#pragma once

#include "cullide/Settings.h"

namespace cullide::test {

/// Reliable mode at `resolution` with every GPU level (exactThreshold 0, GpuLevels::Always).
Settings reliable(int resolution, Pipeline pipeline = Pipeline::Auto);

}  // namespace cullide::test
