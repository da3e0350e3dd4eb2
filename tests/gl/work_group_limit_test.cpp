// Where a pass needs more work groups than the device allows along x (GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]: 65,535 on
// llvmpipe, so no test scene gets there) it is split: map.comp's, group_boxes.comp's and build.comp's dispatches into
// several, the indirect passes into rows of work groups along z, over which the flag pass still finds its last work
// group. With the limit lowered to 2 work groups (GlBackendOptions::maxWorkGroups), every level is held to the
// reference's (lockstep), the mapped positions and the built boxes to the CPU's bit for bit and the pairs to the exact
// reference's.
#include "Compare.h"
#include "CullerBackends.h"
#include "GlTestSupport.h"
#include "Instances.h"
#include "VisibilityLockstep.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <memory>

namespace cullide::test {
namespace {

TEST(WorkGroupLimit, SplitDispatchesKeepWhatTheReferenceKeeps) {
    for (const Backend backend : {Backend::Compute, Backend::Raster}) {
        Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, backend, 64});
        settings.groupSize = 4;  // groups enough for group_boxes.comp's dispatch to be split
        CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
        GlBackendOptions options;
        options.maxWorkGroups = 2;
        auto log = std::make_shared<LockstepLog>();
        std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log, options));
        std::unique_ptr<Culler> reference = createReferenceCuller(settings);
        InstanceScene scene = randomInstances(5, 16, true);
        std::size_t pairs = 0;
        for (int frame = 0; frame < 3; ++frame) {
            Result got;
            const Comparison c = runAndCompare(*culler, *reference, scene.instances(), got);
            EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
            EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
            EXPECT_EQ(c.spurious, 0u) << frame;
            pairs += c.expected;
            for (Transform& t : scene.transforms) t.translation += Vec3(0.013, -0.006, 0.004);
        }
        const char* name = backend == Backend::Raster ? "raster" : "compute";
        EXPECT_EQ(log->mismatches, 0u) << name << ": " << log->summary();
        // Beyond what 2 work groups hold (2 x 64 invocations): every split was taken.
        EXPECT_GT(log->mappedVertices, 4u * 128u) << name << ": " << log->summary();
        EXPECT_GT(log->builtBoxes, log->uploads * 128u) << name << ": " << log->summary();
        EXPECT_GT(log->itemsIn, 4u * 128u) << name << ": " << log->summary();
        EXPECT_GT(log->itemsPruned, 0u) << name << ": " << log->summary();
        EXPECT_GT(pairs, 10u) << name << ": too sparse to test anything";
    }
}

}  // namespace
}  // namespace cullide::test
