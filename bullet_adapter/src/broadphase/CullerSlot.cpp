#include "broadphase/CullerSlot.h"

#include "broadphase/CullingPolicy.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

namespace cullide::bullet {

CullerSlot::CullerSlot(const Settings& settings, Factory factory, double defaultMargin)
    : m_settings(settings), m_factory(std::move(factory)) {
    if (!m_factory) m_factory = [](const Settings& s) { return createGpuCuller(s); };
    const std::string error = m_settings.validate();
    if (!error.empty()) throw std::invalid_argument("cullide::CullideBroadphase: invalid settings: " + error);
    const bool gpuDemanded = m_settings.gpuLevels == GpuLevels::Always || m_settings.pipeline == Pipeline::Paper;
    if (gpuDemanded) make(m_settings.margin > 0.0 ? m_settings.margin : defaultMargin);
}

CullerSlot::~CullerSlot() {
    if (m_pending.valid()) m_pending.wait();  // the other thread's culler goes with this slot
}

/// A culler with margin d from the factory (throws on failure).
std::unique_ptr<Culler> CullerSlot::build(double d) const {
    Settings s = m_settings;
    s.margin = d;
    // Bullet's triangle routines are the exact stage here: the culler hands over its surviving candidates.
    s.exactTriangles = false;
    std::unique_ptr<Culler> made = m_factory(s);
    if (!made) throw std::runtime_error("cullide::CullideBroadphase: the culler factory returned nothing");
    return made;
}

/// Replaces the culler by one with margin d; on failure (throws) the current culler stays as it was.
void CullerSlot::make(double d) {
    m_culler = build(d);
    m_margin = m_culler->settings().margin;
}

void CullerSlot::collectPending() {
    if (!m_pending.valid() || m_pending.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    try {
        m_culler = m_pending.get();
        m_margin = m_culler->settings().margin;
    } catch (const std::exception& e) {
        reportFailure(e);
        if (m_culler == nullptr) m_firstFailed = true;
        else if (m_pendingMargin < m_margin) m_shrinkFailed = true;
    }
}

bool CullerSlot::readyWithoutWaiting(double required, std::uint64_t step) {
    collectPending();
    if (m_culler == nullptr && m_firstFailed) return false;
    if (!m_pending.valid()) {
        if (const auto d = cullingMarginToMake(required, m_margin, m_settings.margin, step, m_shrinkFailed)) {
            m_pendingMargin = *d;
            m_pending = std::async(std::launch::async, [this, d = *d] { return build(d); });
        }
    }
    return m_culler != nullptr && required <= m_margin;
}

bool CullerSlot::ready(double required, std::uint64_t step) {
    if (m_pending.valid()) {  // a switch turned On while Auto's culler was being made: wait for it
        m_pending.wait();
        collectPending();
    }
    if (m_culler == nullptr && m_firstFailed) return false;
    try {
        // With no culler yet (margin 0) the policy always gives a margin: the one the frame needs.
        if (const auto d = cullingMarginToMake(required, m_margin, m_settings.margin, step, m_shrinkFailed)) make(*d);
        return true;
    } catch (const std::exception& e) {
        reportFailure(e);
        if (m_culler == nullptr) {
            m_firstFailed = true;
            return false;
        }
        // A culler that could not be made smaller is still sound; one whose margin is too small is not.
        const bool usable = required <= m_margin;
        if (usable) m_shrinkFailed = true;
        return usable;
    }
}

bool CullerSlot::run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& pairs, Result& result,
                     double budgetMs) {
    result.clear();
    try {
        if (budgetMs > 0.0)
            m_culler->run(objects, pairs, result, budgetMs);
        else
            m_culler->run(objects, pairs, result);
        return true;
    } catch (const std::exception& e) {
        reportFailure(e);
        return false;
    }
}

void CullerSlot::reportFailure(const std::exception& e) {
    if (m_failureReported) return;
    m_failureReported = true;
    std::fprintf(stderr,
                 "cullide::CullideBroadphase: the culler failed (%s); Bullet's full algorithms run for such frames "
                 "(reported once)\n",
                 e.what());
}

}  // namespace cullide::bullet
