// The culler interface and its two implementations: the GPU visibility culler (CULLIDE) and a brute-force CPU
// reference used as the oracle in tests.
#pragma once

#include "cullide/Object.h"
#include "cullide/Result.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace cullide {

/// Thrown when no usable headless OpenGL device is available; the message names what is missing and the package
/// providing it.
class GlUnavailableError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Two objects of a frame by index, first < second.
using ObjectIndexPair = std::pair<std::uint32_t, std::uint32_t>;

class Culler {
public:
    virtual ~Culler() = default;
    Culler() = default;
    Culler(const Culler&) = delete;
    Culler& operator=(const Culler&) = delete;

    /// Runs one frame. Object i of `objects` is object i of the result. Invalid objects (non-finite coordinates or
    /// boxes, out-of-range indices) are listed in Result::rejected and take part in nothing.
    virtual void run(const std::vector<Object>& objects, Result& result) = 0;
    /// Runs one frame over the listed object pairs only: for a caller with an object level of its own (a
    /// broadphase that knows which pairs read triangles). A pair not listed is neither tested nor reported; a listed
    /// pair is reported exactly as run(objects, result) would report it. An object in no listed pair costs its
    /// validation only (its world vertices are never built). `only` must be sorted, without repeats, each
    /// first < second < objects.size(): std::invalid_argument otherwise (nothing is run).
    virtual void run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& only,
                     Result& result) = 0;
    /// run(objects, only, result) within a time budget: a frame that has taken `budgetMs` when it looks (between its
    /// stages, its visibility levels and its exact-stage tasks) is abandoned: `result` then holds no pair and
    /// Stats::abandoned is set, and the caller decides that frame without the culler. budgetMs <= 0: no budget. The
    /// culler stays usable. The default implementation (the reference cullers) ignores the budget.
    virtual void run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& only, Result& result,
                     double budgetMs) {
        (void)budgetMs;
        run(objects, only, result);
    }
    virtual const Settings& settings() const = 0;
};

/// The CULLIDE GPU culler. Throws std::invalid_argument for invalid settings. GL is only needed for GPU levels:
/// with GpuLevels::Never no GL context is opened at all, and with GpuLevels::Auto none unless the device it would use
/// is a hardware one (hasHardwareGlDevice): a software renderer never wins Auto's trial, so the culler runs the CPU
/// path there without opening a context (Stats::gpuUnavailable says so). With GpuLevels::Auto and no usable GL
/// device at all the culler runs the CPU path (box pre-pass, per-object box trees, exact stage: the same results)
/// after a one-line notice on stderr (once per process and reason), and Stats::gpuUnavailable says why
/// (Stats::device "none"); where GPU levels are demanded (GpuLevels::Always, Pipeline::Paper) it throws
/// GlUnavailableError without a usable GL device.
std::unique_ptr<Culler> createGpuCuller(const Settings& settings);

/// Whether the GL device that `device` (as Settings::device: "" for the environment variable CULLIDE_GL_DEVICE, else
/// automatic) selects is a hardware one, found by EGL device enumeration without opening a display or context (the
/// EGL library is loaded; no GL driver is initialised). False for "software" and "surfaceless", for a device index
/// naming Mesa's software device, and where EGL offers no device enumeration. Answered once per process and value.
bool hasHardwareGlDevice(const std::string& device = "");

/// The CULLIDE culler with its image-space visibility test computed on the CPU by the reference implementation
/// (ReferenceVisibility: the shaders' float arithmetic, pixel for pixel; the GL tests hold the GPU to exactly its
/// answers, level by level and iteration by iteration). No GL; single-threaded and slow (resolution² pixels per view
/// and iteration): for checking a device's answers and studying the levels (e.g. sampled mode's misses against
/// resolution), not for production. Settings as for createGpuCuller: GpuLevels::Always runs the levels every frame.
std::unique_ptr<Culler> createVisibilityReferenceCuller(const Settings& settings);

/// All triangle pairs, exact: the oracle. Only margin and threads of the settings are used.
std::unique_ptr<Culler> createReferenceCuller(const Settings& settings);

}  // namespace cullide
