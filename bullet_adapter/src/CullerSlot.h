// The broadphase's culler: made by the application's factory (createGpuCuller by default), with the distance margin
// the frame's pairs need (cullingMarginToMake), and what happens when making or running it fails: the frame's pairs
// get no record, so the dispatcher runs Bullet's full algorithms for them (reported once).
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

    /// Makes the first culler (so that a missing GL device or bad settings show at construction): with the
    /// requested margin, or `defaultMargin` when none is requested. Throws std::invalid_argument for invalid settings.
    CullerSlot(const Settings& settings, Factory factory, double defaultMargin);

    /// A culler whose margin covers `required` at step `step`, recreated per cullingMarginToMake; false when there
    /// is none (making one failed and the current one's margin is too small).
    bool ready(double required, std::uint64_t step);
    /// Runs the culler on the listed pairs; false when it failed.
    bool run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& pairs, Result& result);

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
    bool m_failureReported = false;
};

}  // namespace cullide::bullet
