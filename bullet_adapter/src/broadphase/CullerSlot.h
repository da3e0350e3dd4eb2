// The broadphase's culler: made by the application's factory (createGpuCuller by default) when a frame first has
// pairs for it, with the distance margin the frame's pairs need (cullingMarginToMake), and what happens when making
// or running it fails: the frame's pairs get no record, so the dispatcher runs Bullet's full algorithms for them
// (reported once). A world whose pairs never go through the culler never makes one: no GL context, no worker threads.
// For Culling::Auto the culler is made on another thread (readyWithoutWaiting): no step waits for a GL context or
// shader compilation; the culled pairs run Bullet's algorithms until it is there.
#pragma once

#include "cullide/Culler.h"
#include "cullide/Result.h"
#include "cullide/Settings.h"

#include <cstdint>
#include <exception>
#include <functional>
#include <future>
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
    /// ready() without making anything on the calling thread: a culler that must be made (first, or with another
    /// margin) is made on another thread, and this is false until it is there and large enough.
    bool readyWithoutWaiting(double required, std::uint64_t step);
    /// Runs the culler on the listed pairs within `budgetMs` (0: none; Culler::run with a budget: an abandoned frame
    /// sets result.stats.abandoned and lists nothing); false when it failed.
    bool run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& pairs, Result& result,
             double budgetMs = 0.0);
    ~CullerSlot();
    CullerSlot(const CullerSlot&) = delete;
    CullerSlot& operator=(const CullerSlot&) = delete;

    /// Whether a culler exists (of any margin).
    bool hasCuller() const { return m_culler != nullptr; }
    /// The culler's margin; 0 before one is made.
    double margin() const { return m_margin; }
    const Settings& settings() const { return m_settings; }

private:
    void make(double margin);
    std::unique_ptr<Culler> build(double margin) const;
    /// Installs the culler made on the other thread, once it is there.
    void collectPending();
    void reportFailure(const std::exception& e);

    Settings m_settings;
    Factory m_factory;
    std::unique_ptr<Culler> m_culler;
    double m_margin = 0.0;
    bool m_shrinkFailed = false;  ///< recreating the culler with a smaller margin failed once: not tried again
    bool m_firstFailed = false;   ///< making the first culler failed: not tried again
    bool m_failureReported = false;
    std::future<std::unique_ptr<Culler>> m_pending;  ///< a culler being made on another thread (readyWithoutWaiting)
    double m_pendingMargin = 0.0;
};

}  // namespace cullide::bullet
