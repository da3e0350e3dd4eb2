// The reference culler and object validation (no GL needed): crossing and touching pairs only, the margin, invalid
// objects rejected without harming the others, large meshes checked whole, box proxies.
#include "Compare.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace cullide::test {
namespace {

TriangleMesh singleTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    TriangleMesh m;
    m.vertices = {a, b, c};
    m.triangles = {{0, 1, 2}};
    return m;
}

TEST(ReferenceCuller, FindsCrossingAndTouchingPairsOnly) {
    std::vector<TriangleMesh> meshes = {
        singleTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}),
        singleTriangle({0.2, 0.2, -0.5}, {0.2, 0.2, 0.5}, {0.9, 0.9, 0}),  // crosses 0
        singleTriangle({1, 0, 0}, {2, 0, 0}, {2, 1, 0}),                  // touches 0 at a vertex
        singleTriangle({5, 5, 5}, {6, 5, 5}, {5, 6, 5}),                  // far away
    };
    auto culler = createReferenceCuller(Settings{});
    Result r;
    culler->run(asObjects(meshes), r);
    ASSERT_EQ(r.pairs.size(), 2u);
    EXPECT_EQ(r.pairs[0].a, 0u);
    EXPECT_EQ(r.pairs[0].b, 1u);
    EXPECT_EQ(r.pairs[1].a, 0u);
    EXPECT_EQ(r.pairs[1].b, 2u);
    EXPECT_EQ(r.pcs, (std::vector<std::uint32_t>{0, 1, 2}));
}

TEST(ReferenceCuller, MarginReportsNearPairs) {
    std::vector<TriangleMesh> meshes = {singleTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}),
                                        singleTriangle({0, 0, 0.05}, {1, 0, 0.05}, {0, 1, 0.05})};
    Settings s;
    auto plain = createReferenceCuller(s);
    s.margin = 0.06;
    auto withMargin = createReferenceCuller(s);
    Result r0, r1;
    plain->run(asObjects(meshes), r0);
    withMargin->run(asObjects(meshes), r1);
    EXPECT_TRUE(r0.pairs.empty());
    ASSERT_EQ(r1.pairs.size(), 1u);
    EXPECT_EQ(r1.pairs[0].triangles.size(), 1u);
}

TEST(ReferenceCuller, InvalidObjectsAreRejectedWithoutHarmingOthers) {
    std::vector<TriangleMesh> meshes = {
        singleTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}),
        singleTriangle({0.2, 0.2, -0.5}, {0.2, 0.2, 0.5}, {0.9, 0.9, 0}),
        singleTriangle({0.2, 0.2, -0.5}, {std::nan(""), 0.2, 0.5}, {0.9, 0.9, 0}),
        singleTriangle({0.2, 0.2, -0.5}, {0.2, 0.2, 0.5}, {0.9, 0.9, 0}),
        TriangleMesh{},  // empty mesh: valid, collides with nothing
    };
    meshes[3].triangles[0][2] = 7;  // out of range
    auto objects = asObjects(meshes);
    Object box;
    box.box.min = Vec3(0, 0, 0);
    box.box.max = Vec3(std::numeric_limits<double>::infinity(), 1, 1);
    objects.push_back(box);
    auto culler = createReferenceCuller(Settings{});
    Result r;
    culler->run(objects, r);
    ASSERT_EQ(r.rejected.size(), 3u);
    EXPECT_EQ(r.rejected[0].object, 2u);
    EXPECT_NE(r.rejected[0].message.find("non-finite"), std::string::npos);
    EXPECT_EQ(r.rejected[1].object, 3u);
    EXPECT_NE(r.rejected[1].message.find("out of range"), std::string::npos);
    EXPECT_EQ(r.rejected[2].object, 5u);
    ASSERT_EQ(r.pairs.size(), 1u);
    EXPECT_EQ(r.pairs[0].a, 0u);
    EXPECT_EQ(r.pairs[0].b, 1u);
}

TEST(ReferenceCuller, LargeMeshesAreCheckedWholeAndReportTheirFirstDefect) {
    // Meshes are validated in ranges of triangles (on workers in the GPU culler): the box must still span every
    // range and the message name the first defect in triangle order, whichever range finds one first.
    constexpr std::uint32_t kTriangles = 50000;
    TriangleMesh strip;
    for (std::uint32_t i = 0; i <= kTriangles; ++i) {
        strip.vertices.emplace_back(0.001 * i, 0.0, 0.0);
        strip.vertices.emplace_back(0.001 * i, 1.0, 0.0);
    }
    for (std::uint32_t i = 0; i < kTriangles; ++i) strip.triangles.push_back({2 * i, 2 * i + 1, 2 * i + 2});
    TriangleMesh broken = strip;
    broken.triangles[45000][1] = 9999999;                                         // out of range, later
    broken.vertices[broken.triangles[20000][2]].y() = std::nan("");              // non-finite, first
    broken.triangles[30000][0] = 9999999;                                         // out of range, between
    // A triangle crossing the strip's last triangles only: found only if the last range counts in the box.
    const double x = 0.001 * (kTriangles - 1);
    const TriangleMesh probe = singleTriangle({x, 0.5, -0.5}, {x, 0.5, 0.5}, {x + 0.01, 0.5, 0.0});
    TriangleMesh infinite = strip;  // an infinity (not a NaN), and an unused non-finite vertex: the latter is fine
    infinite.vertices[infinite.triangles[40000][1]].z() = std::numeric_limits<double>::infinity();
    TriangleMesh unusedNaN = probe;
    unusedNaN.vertices.emplace_back(std::nan(""), 0.0, 0.0);
    const std::vector<TriangleMesh> meshes = {strip, broken, probe, infinite, unusedNaN};
    auto culler = createReferenceCuller(Settings{});
    Result r;
    culler->run(asObjects(meshes), r);
    ASSERT_EQ(r.rejected.size(), 2u);
    EXPECT_EQ(r.rejected[0].object, 1u);
    EXPECT_NE(r.rejected[0].message.find("(triangle 20000) has a non-finite coordinate"), std::string::npos)
        << r.rejected[0].message;
    EXPECT_EQ(r.rejected[1].object, 3u);
    EXPECT_NE(r.rejected[1].message.find("(triangle 40000) has a non-finite coordinate"), std::string::npos)
        << r.rejected[1].message;
    // The strip pairs with the probe, and with the probe's copy whose unused NaN vertex is ignored; the probes
    // overlap each other.
    ASSERT_EQ(r.pairs.size(), 3u);
    EXPECT_EQ(r.pairs[0].a, 0u);
    EXPECT_EQ(r.pairs[0].b, 2u);
    EXPECT_FALSE(r.pairs[0].triangles.empty());
    EXPECT_EQ(r.pairs[1].a, 0u);
    EXPECT_EQ(r.pairs[1].b, 4u);
    EXPECT_EQ(r.pairs[2].a, 2u);
    EXPECT_EQ(r.pairs[2].b, 4u);
}

TEST(ReferenceCuller, BoxProxiesPairWithoutTriangles) {
    std::vector<TriangleMesh> meshes = {singleTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0})};
    auto objects = asObjects(meshes);
    Object box;
    box.box.min = Vec3(0.1, 0.1, -0.1);
    box.box.max = Vec3(0.3, 0.3, 0.1);
    objects.push_back(box);
    auto culler = createReferenceCuller(Settings{});
    Result r;
    culler->run(objects, r);
    ASSERT_EQ(r.pairs.size(), 1u);
    EXPECT_FALSE(r.pairs[0].hasTriangles);
}

}  // namespace
}  // namespace cullide::test
