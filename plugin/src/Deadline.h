// A moment by which a stage of the frame must have finished (Culler::run's budget, a GPU trial frame's budget), and
// what a stage throws when it finds the moment passed. Stages look at it where they hold nothing half done: between
// levels, before a tree build, at the start of an exact-stage task; the frame's one wait for the device ends at it.
#pragma once

#include <chrono>
#include <optional>

namespace cullide {

class Deadline {
public:
    /// No deadline: never expired.
    Deadline() = default;
    /// `ms` from `start`; no deadline for ms <= 0.
    static Deadline after(std::chrono::steady_clock::time_point start, double ms) {
        Deadline d;
        if (ms > 0.0)
            d.m_at = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                 std::chrono::duration<double, std::milli>(ms));
        return d;
    }
    /// The earlier of two deadlines (either may be none).
    static Deadline earlier(const Deadline& a, const Deadline& b) {
        if (!a.m_at) return b;
        if (!b.m_at) return a;
        return *a.m_at <= *b.m_at ? a : b;
    }
    bool expired() const { return m_at && std::chrono::steady_clock::now() > *m_at; }
    /// The moment itself (none: never).
    const std::optional<std::chrono::steady_clock::time_point>& at() const { return m_at; }
    explicit operator bool() const { return m_at.has_value(); }

private:
    std::optional<std::chrono::steady_clock::time_point> m_at;
};

/// Thrown by a stage that finds the frame's run budget spent (FrameState::runDeadline): the culler abandons the frame.
struct RunAbandoned {};

}  // namespace cullide
