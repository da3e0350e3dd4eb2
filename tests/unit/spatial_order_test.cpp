// The spatial order of a whole mesh (spatialOrder, TriangleOrders.h): a permutation of its triangles along the
// Morton curve, the same on any number of workers.
#include "TriangleOrders.h"
#include "TriangleRow.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

namespace cullide::test {
namespace {

TEST(SpatialOrder, APermutationAlongTheMortonCurveOnAnyNumberOfWorkers) {
    constexpr std::uint32_t kTriangles = 1000;  // under 1,024 cells along x: one triangle per cell
    const TriangleMesh row = triangleRow(kTriangles);
    std::vector<std::uint32_t> serial;
    spatialOrder(row, serial);
    ASSERT_EQ(serial.size(), kTriangles);
    for (std::size_t i = 1; i < serial.size(); ++i)
        ASSERT_LT(row.vertices[row.triangles[serial[i - 1]][0]][0], row.vertices[row.triangles[serial[i]][0]][0]);
    const TriangleMesh sphere = scenes::makeSphere(1.0, 200, 100);
    spatialOrder(sphere, serial);
    std::vector<std::uint32_t> sorted = serial;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::uint32_t> identity(sphere.triangles.size());
    std::iota(identity.begin(), identity.end(), 0u);
    EXPECT_EQ(sorted, identity);
    TaskPool three(3);
    std::vector<std::uint32_t> onThree;
    spatialOrder(sphere, onThree, &three);
    EXPECT_EQ(onThree, serial);
}

}  // namespace
}  // namespace cullide::test
