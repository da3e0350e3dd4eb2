#include "GlTestSupport.h"

#include <cstdlib>
#include <cstring>

namespace cullide::test {

bool runningInCi() {
    const char* ci = std::getenv("CI");
    return ci != nullptr && (std::strcmp(ci, "true") == 0 || std::strcmp(ci, "1") == 0);
}

std::unique_ptr<Culler> makeGpuCuller(const Settings& settings, std::string& whyNot) {
    std::unique_ptr<Culler> culler;
    try {
        culler = createGpuCuller(settings);
    } catch (const GlUnavailableError& e) {
        whyNot = e.what();
        return nullptr;
    }
    // Without a GL device the culler still runs (the CPU path, with GpuLevels::Auto); a GL test wants the device.
    if (settings.gpuLevels != GpuLevels::Never) {
        Result probe;
        culler->run({}, probe);
        if (!probe.stats.gpuUnavailable.empty()) {
            whyNot = probe.stats.gpuUnavailable;
            return nullptr;
        }
    }
    return culler;
}

std::unique_ptr<SnapshotRenderer> makeSnapshotRenderer(std::string& whyNot) {
    try {
        return SnapshotRenderer::create();
    } catch (const GlUnavailableError& e) {
        whyNot = e.what();
        return nullptr;
    }
}

}  // namespace cullide::test
