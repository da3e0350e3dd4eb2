#include "GlTestSupport.h"

#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <cstring>

namespace cullide::test {

bool runningInCi() {
    const char* ci = std::getenv("CI");
    return ci != nullptr && (std::strcmp(ci, "true") == 0 || std::strcmp(ci, "1") == 0);
}

namespace {

/// Whether a culler can open a GL context on `device` (probed once per process and device).
bool glDeviceUsable(const std::string& device, std::string& whyNot) {
    static std::mutex mutex;
    static std::map<std::string, std::string> reasons;  // "" = usable
    const std::lock_guard<std::mutex> lock(mutex);
    auto it = reasons.find(device);
    if (it == reasons.end()) {
        Settings demanding;
        demanding.gpuLevels = GpuLevels::Always;
        demanding.device = device;
        std::string why;
        try {
            createGpuCuller(demanding);
        } catch (const GlUnavailableError& e) {
            why = e.what();
        }
        it = reasons.emplace(device, why).first;
    }
    whyNot = it->second;
    return whyNot.empty();
}

}  // namespace

std::unique_ptr<Culler> makeGpuCuller(const Settings& settings, std::string& whyNot) {
    std::unique_ptr<Culler> culler;
    try {
        culler = createGpuCuller(settings);
    } catch (const GlUnavailableError& e) {
        whyNot = e.what();
        return nullptr;
    }
    // Without a GL device the culler still runs (the CPU path, with GpuLevels::Auto); a GL test wants the device.
    // With GpuLevels::Auto the culler itself opens no context on a software renderer (it never runs GPU levels
    // there), so the device is probed with GPU levels demanded, once per process and device.
    if (settings.gpuLevels == GpuLevels::Auto && !glDeviceUsable(settings.device, whyNot)) return nullptr;
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
