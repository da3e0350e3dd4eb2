// Object pairs and triangle pairs reported for one frame, normalised (first object < second) and sorted, and the
// comparison with the exact answer. Also the binary "truth" file that carries the exact answer between processes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace cullide::bench {

/// (object a, triangle of a, object b, triangle of b) with a < b.
using TriangleKey = std::array<std::uint32_t, 4>;
/// (object a, object b) with a < b.
using ObjectKey = std::array<std::uint32_t, 2>;

class PairSet {
public:
    void addTriangle(std::uint32_t a, std::uint32_t ta, std::uint32_t b, std::uint32_t tb);
    void addObject(std::uint32_t a, std::uint32_t b);
    /// Sorts, removes duplicates and adds the object pair of every triangle pair.
    void finish();
    void clear();

    const std::vector<TriangleKey>& triangles() const { return m_triangles; }
    const std::vector<ObjectKey>& objects() const { return m_objects; }

private:
    std::vector<TriangleKey> m_triangles;
    std::vector<ObjectKey> m_objects;
};

/// How a reported set compares with the exact one.
struct Comparison {
    std::size_t expected = 0;
    std::size_t reported = 0;
    std::size_t missed = 0;  ///< in the exact set, not reported
    std::size_t extra = 0;   ///< reported, not in the exact set
    Comparison& operator+=(const Comparison& o);
};

/// Both inputs sorted and unique.
Comparison compareTriangles(const std::vector<TriangleKey>& exact, const std::vector<TriangleKey>& reported);
Comparison compareObjects(const std::vector<ObjectKey>& exact, const std::vector<ObjectKey>& reported);

/// The exact answer of several frames, keyed by frame index.
using Truth = std::map<int, PairSet>;
void writeTruth(const std::string& path, const Truth& truth);
/// Throws std::runtime_error when the file is missing or malformed.
Truth readTruth(const std::string& path);

}  // namespace cullide::bench
