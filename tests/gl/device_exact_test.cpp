// The device exact stage (Settings::deviceExact, shaders/exact.comp): its pairs and its filter's verdicts are the CPU
// reference's (DeviceExact.h) in lockstep, the culler's pairs are those of the CPU's exact stage — near contacts,
// margins, far from the origin — and a buffer too small for the frame's pairs sends that frame's exact stage to the CPU
// and grows.
#include "Compare.h"
#include "CullerBackends.h"
#include "GlTestSupport.h"
#include "ReliableSettings.h"
#include "VisibilityLockstep.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

namespace cullide::test {
namespace {

/// Two interpenetrating spheres of many triangles and a third touching them, shifted by `offset`.
std::vector<TriangleMesh> nearContacts(const Vec3& offset) {
    std::vector<TriangleMesh> meshes;
    const std::pair<Vec3, double> spheres[] = {{Vec3(0.0, 0.0, 0.0), 1.0}, {Vec3(1.5, 0.2, 0.1), 0.8},
                                               {Vec3(0.2, 1.6, 0.0), 0.6}};
    for (const auto& [centre, radius] : spheres) {
        meshes.push_back(scenes::makeSphere(radius, 24, 12));
        scenes::transformMesh(meshes.back(), Eigen::Affine3d(Eigen::Translation3d(centre + offset)));
    }
    return meshes;
}

Settings deviceExact(double margin) {
    Settings s = reliable(64, Pipeline::Auto);
    s.margin = margin;
    return s;
}

TEST(DeviceExact, PairsAndVerdictsAreTheReferencesInLockstep) {
    for (double margin : {0.0, 0.01}) {
        Settings settings = deviceExact(margin);
        CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
        auto log = std::make_shared<LockstepLog>();
        auto culler = createGpuCuller(settings, lockstepFactory(log));
        const auto meshes = nearContacts(Vec3::Zero());
        const auto objects = asObjects(meshes);
        Result r;
        for (int frame = 0; frame < 2; ++frame) culler->run(objects, r);
        EXPECT_EQ(log->mismatches, 0u) << log->summary();
        EXPECT_GT(r.stats.deviceExactClusters, 0u);
        EXPECT_GT(log->exactPairs, 0u) << log->summary();
        EXPECT_GT(log->exactCertified, 0u) << "the filter certified no pair";
        EXPECT_LT(log->exactCertified, log->exactPairs) << "no pair left to the CPU's predicate";
    }
}

TEST(DeviceExact, TheSamePairsAsTheCpuExactStageNearTheOriginAndFarFromIt) {
    for (const Vec3& offset : {Vec3(0.0, 0.0, 0.0), Vec3(1e6, -2e6, 3e5)}) {
        for (double margin : {0.0, 0.02}) {
            for (bool exactTriangles : {true, false}) {
                Settings on = deviceExact(margin);
                on.exactTriangles = exactTriangles;
                CULLIDE_GPU_CULLER_OR_SKIP(device, on);
                Settings off = on;
                off.deviceExact = DeviceExact::Never;
                auto cpu = createGpuCuller(off);
                const auto meshes = nearContacts(offset);
                const auto objects = asObjects(meshes);
                Result got, expected;
                device->run(objects, got);
                cpu->run(objects, expected);
                const std::string name = "offset " + std::to_string(offset.x()) + ", margin " +
                                         std::to_string(margin) + (exactTriangles ? ", exact" : ", candidates");
                EXPECT_GT(got.stats.deviceExactPairs, 0u) << name;
                EXPECT_EQ(expected.stats.deviceExactPairs, 0u) << name;
                EXPECT_EQ(trianglePairs(got), trianglePairs(expected)) << name;
                EXPECT_EQ(got.stats.intersectingTrianglePairs, expected.stats.intersectingTrianglePairs) << name;
                if (exactTriangles) {
                    Result reference;
                    Settings rs;
                    rs.margin = margin;
                    createReferenceCuller(rs)->run(objects, reference);
                    EXPECT_EQ(trianglePairs(got), trianglePairs(reference)) << name;
                }
            }
        }
    }
}

TEST(DeviceExact, AFrameWhosePairsOverflowTheBufferFinishesOnTheCpuAndTheBufferGrows) {
    Settings settings = deviceExact(0.0);
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    GlBackendOptions options;
    options.exactCapacity = 4;
    auto culler =
        createGpuCuller(settings, [options](const Settings& s) { return createGlPruningBackend(s, options); });
    Settings off = settings;
    off.deviceExact = DeviceExact::Never;
    const auto meshes = nearContacts(Vec3::Zero());
    const auto objects = asObjects(meshes);
    Result expected;
    createGpuCuller(off)->run(objects, expected);
    Result first, second;
    culler->run(objects, first);
    EXPECT_GT(first.stats.deviceExactOverflows, 0u);
    EXPECT_EQ(trianglePairs(first), trianglePairs(expected));
    culler->run(objects, second);
    EXPECT_EQ(second.stats.deviceExactOverflows, 0u) << "the buffer did not grow";
    EXPECT_GT(second.stats.deviceExactPairs, 4u);
    EXPECT_EQ(trianglePairs(second), trianglePairs(expected));
}

TEST(DeviceExact, WhereOnlyALaterClusterOverflowsTheEarlierKeepsItsDevicePairs) {
    // Two copies of the scene far apart: two clusters, whose pairs share the frame's buffer one after the other.
    Settings settings = deviceExact(0.0);
    CULLIDE_GPU_CULLER_OR_SKIP(single, settings);
    const auto one = nearContacts(Vec3::Zero());
    Result alone;
    single->run(asObjects(one), alone);
    const std::size_t perCluster = alone.stats.deviceExactPairs;
    ASSERT_GT(perCluster, 0u);
    auto meshes = one;
    for (const TriangleMesh& m : nearContacts(Vec3(1000.0, 0.0, 0.0))) meshes.push_back(m);
    const auto objects = asObjects(meshes);
    Settings off = settings;
    off.deviceExact = DeviceExact::Never;
    Result expected;
    createGpuCuller(off)->run(objects, expected);
    GlBackendOptions options;
    options.exactCapacity = perCluster;  // the first cluster's pairs fit exactly, the second's do not
    auto culler =
        createGpuCuller(settings, [options](const Settings& s) { return createGlPruningBackend(s, options); });
    Result got;
    culler->run(objects, got);
    EXPECT_EQ(got.stats.clusters, 2u);
    EXPECT_EQ(got.stats.deviceExactOverflows, 1u);
    EXPECT_EQ(got.stats.deviceExactClusters, 1u);
    EXPECT_EQ(got.stats.deviceExactPairs, perCluster);
    EXPECT_EQ(trianglePairs(got), trianglePairs(expected));
    culler->run(objects, got);
    EXPECT_EQ(got.stats.deviceExactOverflows, 0u);
    EXPECT_EQ(got.stats.deviceExactClusters, 2u);
    EXPECT_EQ(trianglePairs(got), trianglePairs(expected));
}

}  // namespace
}  // namespace cullide::test
