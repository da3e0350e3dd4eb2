// writeOff: meshes round-trip exactly through the OFF writer and reader.
#include "ReaderSupport.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>

namespace cullide::io {
namespace {

using namespace cullide::test;

TEST(WriteOff, RoundTripsExactly) {
    TriangleMesh m;
    std::mt19937_64 gen(3);
    for (int i = 0; i < 200; ++i) {
        const double scale = std::ldexp(1.0, static_cast<int>(gen() % 200) - 100);
        m.vertices.emplace_back((static_cast<double>(gen() >> 11) * 0x1p-53 - 0.5) * scale, -0.0,
                                i == 0 ? 5e-324 : 1.0 / (i + 1));
    }
    for (std::uint32_t i = 0; i + 2 < 200; ++i) m.triangles.push_back({i, i + 1, i + 2});
    std::ostringstream out;
    writeOff(m, out);
    const TriangleMesh back = off(out.str());
    ASSERT_EQ(back.vertices.size(), m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) EXPECT_EQ(back.vertices[i], m.vertices[i]) << i;
    EXPECT_EQ(back.triangles, m.triangles);
    // Empty mesh.
    std::ostringstream e;
    writeOff(TriangleMesh{}, e);
    EXPECT_TRUE(off(e.str()).vertices.empty());
}

}  // namespace
}  // namespace cullide::io
