#include "cullide/Settings.h"

#include <cmath>
#include <string>

namespace cullide {
namespace {

/// The device names EglContext understands: none (its default order), a kind, or an index of EGL's device list.
bool deviceNameValid(const std::string& device) {
    if (device.empty() || device == "hardware" || device == "software" || device == "surfaceless") return true;
    if (device.size() > 4 || (device.size() > 1 && device[0] == '0')) return false;  // as std::to_string writes it
    for (const char c : device)
        if (c < '0' || c > '9') return false;
    return true;
}

}  // namespace

std::string Settings::validate() const {
    if (resolution < 16 || resolution > 4096) return "resolution must be in 16..4096";
    if (groupSize < 1 || groupSize > 4096) return "groupSize must be in 1..4096";
    if (axes < 1 || axes > 7) return "axes must be a non-empty bit mask of x=1, y=2, z=4";
    if (maxIterations < 1 || maxIterations > 64) return "maxIterations must be in 1..64";
    if (!(minPruneFraction >= 0.0 && minPruneFraction <= 1.0)) return "minPruneFraction must be in 0..1";
    if (!std::isfinite(margin) || margin < 0.0) return "margin must be finite and >= 0";
    if (threads > 256) return "threads must be <= 256";
    if (!deviceNameValid(device))
        return "device must be \"\", \"hardware\", \"software\", \"surfaceless\" or an EGL device index such as "
               "\"0\" (got \"" + device.substr(0, 64) + "\")";
    if (mode != Mode::Reliable && mode != Mode::Sampled) return "mode is not a Mode value";
    if (pipeline != Pipeline::Auto && pipeline != Pipeline::Paper) return "pipeline is not a Pipeline value";
    if (backend != Backend::Compute && backend != Backend::Raster) return "backend is not a Backend value";
    if (gpuLevels != GpuLevels::Auto && gpuLevels != GpuLevels::Always && gpuLevels != GpuLevels::Never)
        return "gpuLevels is not a GpuLevels value";
    if (deviceExact != DeviceExact::OnHardware && deviceExact != DeviceExact::Always &&
        deviceExact != DeviceExact::Never)
        return "deviceExact is not a DeviceExact value";
    if (pipeline == Pipeline::Paper && gpuLevels == GpuLevels::Never)
        return "pipeline Paper runs GPU levels by definition: it contradicts gpuLevels Never (use Pipeline::Auto "
               "for the CPU path)";
    return {};
}

}  // namespace cullide
