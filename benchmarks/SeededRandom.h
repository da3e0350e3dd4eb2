// Seeded uniform numbers that are the same on every standard library (the std distributions are not).
#pragma once

#include <LinearMath/btScalar.h>

#include <cstdint>
#include <random>

namespace cullide::bench {

/// Uniform doubles from mt19937_64 with our own mapping, as btScalar.
class SeededRandom {
public:
    explicit SeededRandom(std::uint64_t seed) : m_gen(seed) {}
    btScalar uniform(double lo, double hi) {
        const double u = static_cast<double>(m_gen() >> 11) * (1.0 / 9007199254740992.0);
        return static_cast<btScalar>(lo + (hi - lo) * u);
    }

private:
    std::mt19937_64 m_gen;
};

}  // namespace cullide::bench
