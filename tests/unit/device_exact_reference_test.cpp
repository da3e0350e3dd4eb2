// The device exact stage without GL: the reference backend runs its search and filter on the CPU (DeviceExact.h), and
// the culler's pairs are those of the CPU's exact stage — exact or candidates, with and without a margin, near the
// origin and far from it — while most pairs are decided by the filter, not the CPU's predicate.
#include "Compare.h"
#include "CullerBackends.h"
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

/// The reference backend, saying it runs on a hardware GPU or not (DeviceExact::OnHardware asks).
class ReportingBackend final : public PruningBackend {
public:
    ReportingBackend(const Settings& s, bool hardware)
        : m_inner(createReferencePruningBackend(s)), m_hardware(hardware) {}
    bool hardwareDevice() const override { return m_hardware; }
    void beginFrame() override { m_inner->beginFrame(); }
    void upload(const GpuGeometry& g, Stats& stats) override { m_inner->upload(g, stats); }
    void forgetUploads() override { m_inner->forgetUploads(); }
    std::size_t deviceBytes() const override { return m_inner->deviceBytes(); }
    std::string renderer() const override { return m_inner->renderer(); }
    std::string device() const override { return m_inner->device(); }
    void pruneLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                    LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) override {
        m_inner->pruneLevel(items, start, survivors, level, stats, trace);
    }
    void pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                         std::vector<IterationTrace>* trace) override {
        m_inner->pruneLevelAhead(items, start, levelIndex, stats, trace);
    }
    void settle(Stats& stats) override { m_inner->settle(stats); }
    void pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                            std::vector<IterationTrace>* trace) override {
        m_inner->pruneLevelDeferred(items, start, levelIndex, stats, trace);
    }
    bool collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) override {
        return m_inner->collect(until, results, stats);
    }

private:
    std::unique_ptr<PruningBackend> m_inner;
    bool m_hardware;
};

TEST(DeviceExactReference, OnHardwareRunsTheStageOnlyWhereTheBackendIsAHardwareGpu) {
    const auto meshes = randomSoups(5, 12, 80, 0.6);
    const auto objects = asObjects(meshes);
    Settings s = referenceLevels(Pipeline::Auto, Mode::Reliable, 64);
    EXPECT_EQ(s.deviceExact, DeviceExact::OnHardware) << "the default";
    for (bool hardware : {false, true}) {
        auto culler = createGpuCuller(
            s, [hardware](const Settings& settings) { return std::make_unique<ReportingBackend>(settings, hardware); });
        Result r;
        culler->run(objects, r);
        EXPECT_EQ(r.stats.deviceExactClusters > 0, hardware) << (hardware ? "hardware" : "software");
    }
}

}  // namespace
}  // namespace cullide::test
