// The broadphase's culler: made by the application's factory (createGpuCuller by default) when a frame first has
// pairs for it, with the distance margin the frame's pairs need (cullingMarginToMake), and what happens when making
// or running it fails: the frame's pairs get no record, so the dispatcher runs Bullet's full algorithms for them
// (reported once). A world whose pairs never go through the culler (the default: no culling switch on) never makes
// one: no GL context, no worker threads.
#pragma once

#include "cullide/Culler.h"
#include "cullide/Result.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <vector>

namespace cullide::bullet {

class CullerSlot {
public:
    using Factory = std::function<std::unique_ptr<Culler>(const Settings&)>;

    /// Throws std::invalid_argument for invalid settings. Settings that demand GPU levels (GpuLevels::Always,
    /// Pipeline::Paper) make the culler here, with the requested margin or `defaultMargin`, so that a missing GL
    /// device throws here (GlUnavailableError); otherwise it is made by the first ready().
    CullerSlot(const Settings& settings, Factory factory, double defaultMargin);

    /// A culler whose margin covers `required` at step `step`: made with the margin cullingMarginToMake gives when
    /// there is none yet, recreated per cullingMarginToMake; false when there is none (making the first one failed,
    /// which is not tried again, or making a larger one failed and the current one's margin is too small).
    bool ready(double required, std::uint64_t step);
    /// Runs the culler on the listed pairs; false when it failed.
    bool run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& pairs, Result& result);

    /// The culler's margin; 0 before one is made.
    double margin() const { return m_margin; }
    const Settings& settings() const { return m_settings; }

private:
    void make(double margin);
    void reportFailure(const std::exception& e);

    Settings m_settings;
    Factory m_factory;
    std::unique_ptr<Culler> m_culler;
    double m_margin = 0.0;
    bool m_shrinkFailed = false;  ///< recreating the culler with a smaller margin failed once: not tried again
    bool m_firstFailed = false;   ///< making the first culler failed: not tried again
    bool m_failureReported = false;
};

}  // namespace cullide::bullet
