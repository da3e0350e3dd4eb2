// The device's record buffers: a record build is never waited for, so a build that needs more records than the
// buffers hold finds out on the device (it writes none and its iteration prunes nothing); the culler grows the buffers,
// builds again and keeps them for the next frames. Held to the visibility reference (VisibilityLockstep) and to the
// exact reference culler.
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"

#include <gtest/gtest.h>

#include <memory>

namespace cullide::test {
namespace {

std::size_t shortBuilds(const Result& r) {
    std::size_t n = 0;
    for (const LevelStats& level : r.stats.levels) n += level.shortBuilds;
    return n;
}

/// Short bands (a hardware GPU's: many records per primitive) on a fresh culler: its first build needs more records
/// than the buffers it starts with. The frame still keeps what the reference keeps, iteration by iteration, and
/// finds every exact pair; the next frames fit in the grown buffers. The first build is the group level's, run ahead
/// of the triangle level: its short build is found at the triangle level's read-back, and both levels run again.
TEST(RecordCapacity, AShortBuildIsBuiltAgainAndTheBuffersAreKept) {
    for (const Backend backend : {Backend::Compute, Backend::Raster}) {
        const Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, backend, 256});
        CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
        auto log = std::make_shared<LockstepLog>();
        GlBackendOptions options;
        options.shortBands = true;
        std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log, options));
        std::unique_ptr<Culler> reference = createReferenceCuller(settings);
        const std::vector<TriangleMesh> meshes = randomSoups(3, 12, 60, 0.2);
        const std::vector<Object> objects = asObjects(meshes);  // points into meshes
        std::size_t firstFrameShort = 0, firstFrameReruns = 0;
        for (int frame = 0; frame < 3; ++frame) {
            Result r;
            const Comparison c = runAndCompare(*culler, *reference, objects, r);
            EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
            EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
            EXPECT_GT(c.expected, 0u);
            if (frame == 0) {
                firstFrameShort = shortBuilds(r);
                firstFrameReruns = r.stats.levelReruns;
            } else {
                EXPECT_EQ(shortBuilds(r), 0u) << "frame " << frame << ": the grown buffers were not kept";
                EXPECT_EQ(r.stats.levelReruns, 0u) << "frame " << frame;
            }
        }
        // The raster back-end makes one record per primitive, which the first buffers always hold.
        if (backend == Backend::Compute) {
            // The group level's short build, run ahead, runs both levels again (the first frame issues every
            // iteration allowed, so nothing else stops its chain early); the buffers grew from its needed count
            // as its chain was read, and the short attempt's levels are replaced by the rerun's.
            EXPECT_EQ(firstFrameReruns, 1u) << "the scene must outgrow the first buffers";
            EXPECT_EQ(firstFrameShort, 0u) << "the rerun built short again: the buffers did not grow as the chain was read";
        } else {
            EXPECT_EQ(firstFrameShort, 0u);
            EXPECT_EQ(firstFrameReruns, 0u);
        }
        EXPECT_EQ(log->mismatches, 0u) << log->summary();
        EXPECT_GT(log->itemsPruned, 0u) << log->summary();
    }
}

}  // namespace
}  // namespace cullide::test
