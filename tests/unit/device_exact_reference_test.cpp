// The device exact stage without GL: the reference backend runs its search and filter on the CPU (DeviceExact.h), and
// the culler's pairs are those of the CPU's exact stage — exact or candidates, with and without a margin, near the
// origin and far from it — while most pairs are decided by the filter, not the CPU's predicate.
#include "Compare.h"
#include "ReferenceLevelsSupport.h"

#include <gtest/gtest.h>

#include <string>

namespace cullide::test {
namespace {

/// The culler on the reference backend with the device exact stage (got) and without it (expected).
struct Both {
    Result got;
    Result expected;
};

Both runBoth(const std::vector<Object>& objects, double margin, bool exactTriangles) {
    Settings on = referenceLevels(Pipeline::Auto, Mode::Reliable, 64);
    on.margin = margin;
    on.exactTriangles = exactTriangles;
    on.deviceExact = DeviceExact::Always;
    Settings off = on;
    off.deviceExact = DeviceExact::Never;
    Both both;
    referenceLevelsCuller(on)->run(objects, both.got);
    referenceLevelsCuller(off)->run(objects, both.expected);
    return both;
}

TEST(DeviceExactReference, TheSamePairsAsTheCpuExactStage) {
    for (double offset : {0.0, 1e7}) {
        for (double margin : {0.0, 0.01}) {
            for (bool exactTriangles : {true, false}) {
                auto meshes = randomSoups(5, 12, 80, 0.6);
                for (TriangleMesh& m : meshes)
                    for (Vec3& v : m.vertices) v += Vec3(offset, -offset, 0.5 * offset);
                const auto objects = asObjects(meshes);
                const auto [got, expected] = runBoth(objects, margin, exactTriangles);
                const std::string name = "offset " + std::to_string(offset) + ", margin " + std::to_string(margin) +
                                         (exactTriangles ? ", exact" : ", candidates");
                EXPECT_GT(got.stats.deviceExactClusters, 0u) << name;
                EXPECT_GT(got.stats.deviceExactPairs, 0u) << name;
                EXPECT_EQ(trianglePairs(got), trianglePairs(expected)) << name;
                EXPECT_EQ(got.stats.intersectingTrianglePairs, expected.stats.intersectingTrianglePairs) << name;
                if (exactTriangles) {
                    // The filter decides most: the CPU tests fewer pairs than its own stage had candidates.
                    EXPECT_LT(got.stats.exactTests, expected.stats.exactTests) << name;
                    EXPECT_GT(got.stats.deviceExactCertified, 0u) << name;
                }
            }
        }
    }
}

TEST(DeviceExactReference, ACandidateIsAPairWhoseDoubleBoxesOverlapNotOnlyItsFloatBoxes) {
    // Triangle boxes 1e-9 apart along x: within the device's slack (float error), apart in double. The objects' boxes
    // overlap through a second triangle of the first mesh, far from the other's along y.
    TriangleMesh a, b;
    a.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1.5, 10, 0), Vec3(3, 10, 0), Vec3(1.5, 11, 0)};
    a.triangles = {{0, 1, 2}, {3, 4, 5}};
    b.vertices = {Vec3(1 + 1e-9, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0)};
    b.triangles = {{0, 1, 2}};
    const std::vector<TriangleMesh> meshes = {a, b};
    const auto objects = asObjects(meshes);
    for (bool exactTriangles : {false, true}) {
        const auto [got, expected] = runBoth(objects, 0.0, exactTriangles);
        EXPECT_GT(got.stats.deviceExactPairs, 0u) << "the device did not compare the pair";
        EXPECT_EQ(trianglePairs(got), trianglePairs(expected)) << (exactTriangles ? "exact" : "candidates");
        EXPECT_TRUE(trianglePairs(got).empty());
    }
}

}  // namespace
}  // namespace cullide::test
