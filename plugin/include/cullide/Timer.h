// Wall-clock stage timing (stats of the culler, the Bullet adapter and the tools).
#pragma once

#include <chrono>

namespace cullide {

class Timer {
public:
    Timer() : m_start(std::chrono::steady_clock::now()) {}
    double ms() const {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m_start).count();
    }

private:
    std::chrono::steady_clock::time_point m_start;
};

}  // namespace cullide
