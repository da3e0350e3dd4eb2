// The GPU culler on shared meshes placed by transforms: exactly the reference's pairs, with and without GPU levels,
// both pipelines; static keys with transforms refresh when the transform changes.
#include "Compare.h"
#include "GlTestSupport.h"
#include "Instances.h"
#include "VisibilityLockstep.h"
#include "cullide/scenes/Procedural.h"

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <memory>
#include <set>

namespace cullide::test {
namespace {

Settings withLevels(GpuLevels levels, Pipeline pipeline) {
    Settings s;
    s.resolution = 64;
    s.gpuLevels = levels;
    s.pipeline = pipeline;
    s.exactThreshold = 0;
    return s;
}

struct Case {
    GpuLevels levels;
    Pipeline pipeline;
};

class TransformedInstances : public ::testing::TestWithParam<Case> {};

TEST_P(TransformedInstances, MatchTheReferenceAndTheWorldSpaceTwins) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, withLevels(GetParam().levels, GetParam().pipeline));
    auto reference = createReferenceCuller(Settings{});
    std::size_t total = 0;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        const InstanceScene scene = randomInstances(seed, 24, seed == 2, 4);
        Result expected, got, twins;
        reference->run(scene.worldObjects(), expected);
        culler->run(scene.instances(), got);
        culler->run(scene.worldObjects(), twins);
        const Comparison cmp = compare(expected, got);
        EXPECT_EQ(cmp.missed, 0u) << "seed " << seed << ": " << cmp.firstMissed;
        EXPECT_EQ(cmp.spurious, 0u) << "seed " << seed;
        EXPECT_TRUE(cmp.objectPairsEqual) << "seed " << seed;
        EXPECT_EQ(trianglePairs(got), trianglePairs(twins)) << "seed " << seed;
        total += cmp.expected;
    }
    EXPECT_GT(total, 40u) << "scenes too sparse to test anything";
}

INSTANTIATE_TEST_SUITE_P(Pipelines, TransformedInstances,
                         ::testing::Values(Case{GpuLevels::Never, Pipeline::Auto},
                                           Case{GpuLevels::Always, Pipeline::Auto},
                                           Case{GpuLevels::Always, Pipeline::Paper}));

// Moving instances (rigid and sheared, some far away: clusters of their own) go to the device in their own frames and
// are mapped there (map.comp): every upload's positions are held to the CPU's bit for bit, every level to the
// reference's (lockstep), the pairs to the exact reference's; a frame sends their transforms, not their vertices, and
// a mesh's own vertices again only where they changed.
TEST(TransformedInstances, MovingInstancesAreMappedOnTheDeviceBitForBit) {
    const Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    CULLIDE_GPU_CULLER_OR_SKIP(twinCuller, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    InstanceScene scene = randomInstances(11, 24, true, 6);
    std::size_t pairs = 0, mappedBytes = 0, twinBytes = 0, firstFrameMapped = 0;
    for (int frame = 0; frame < 4; ++frame) {
        Result got, twins;
        const Comparison c = runAndCompare(*culler, *reference, scene.instances(), got);
        EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << frame;
        twinCuller->run(scene.worldObjects(), twins);
        EXPECT_EQ(trianglePairs(got), trianglePairs(twins)) << frame;
        pairs += c.expected;
        if (frame > 0) {  // every instance moved since the last frame
            mappedBytes += got.stats.bytesUploaded;
            twinBytes += twins.stats.bytesUploaded;
        } else {
            firstFrameMapped = log->mappedVertices;
        }
        for (Transform& t : scene.transforms) {
            t.translation += Vec3(0.011, -0.007, 0.005);
            t.linear = Eigen::AngleAxisd(0.03, Vec3(0.3, 1.0, -0.2).normalized()).toRotationMatrix() * t.linear;
        }
        if (frame == 1)  // a shared mesh deforms in its own frame (same address, same counts): sent again
            for (Vec3& v : scene.meshes[0].vertices) v = Vec3(1.2 * v.x(), v.y(), 0.8 * v.z());
        scene.refreshWorldMeshes();
    }
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GT(log->mappedVertices, 0u) << log->summary();
    EXPECT_GT(log->itemsPruned, 0u) << log->summary();
    EXPECT_GT(pairs, 20u) << "too sparse to test anything";
    // The twins send their world vertices again (12 bytes each) where the instances send a transform (112 bytes): under
    // 2 bytes per vertex moved, a quarter of what the twins send at most.
    const std::size_t moved = log->mappedVertices - firstFrameMapped;
    EXPECT_LT(mappedBytes, 2 * moved) << moved << " vertices moved";
    EXPECT_LT(4 * mappedBytes, twinBytes) << moved << " vertices moved";
}

// A static key whose transform changes (same version) must not reuse the boxes of the old placement.
TEST(TransformedInstances, StaticKeyFollowsTheTransform) {
    CULLIDE_GPU_CULLER_OR_SKIP(culler, withLevels(GpuLevels::Never, Pipeline::Auto));
    auto reference = createReferenceCuller(Settings{});
    InstanceScene scene = randomInstances(5, 12, false);
    std::size_t pairs = 0, changes = 0;
    std::set<FlatPair> last;
    for (int frame = 0; frame < 6; ++frame) {
        std::vector<Object> objects = scene.instances();
        for (std::size_t i = 0; i < objects.size(); ++i) objects[i].staticKey = i + 1;  // version stays 0
        Result expected, got;
        reference->run(objects, expected);
        culler->run(objects, got);
        EXPECT_EQ(trianglePairs(got), trianglePairs(expected)) << "frame " << frame;
        pairs += trianglePairs(expected).size();
        changes += trianglePairs(expected) != last ? 1 : 0;
        last = trianglePairs(expected);
        // Every other instance moves on (same key, same version): its placement, not its mesh, changed.
        for (std::size_t i = 0; i < scene.transforms.size(); i += 2)
            scene.transforms[i].translation += Vec3(0.12, -0.07, 0.05);
    }
    EXPECT_GT(pairs, 30u);
    EXPECT_GE(changes, 4u) << "the moves must change the pairs";
}

// Keyed instances in motion (a rigid body's staticKey, its transform changing every frame) keep their checks in their
// own frame, and their group boxes there, between frames: the same pairs as unkeyed instances and the exact
// reference's, every level in lockstep with the reference where GPU levels run; a mesh whose version changes is
// checked again.
class KeyedInstancesInMotion : public ::testing::TestWithParam<Case> {};

/// The potentially colliding triangles of each object.
std::size_t pcsTriangles(const Result& r) {
    std::size_t n = 0;
    for (const auto& list : r.pcsTriangles) n += list.size();
    return n;
}

TEST_P(KeyedInstancesInMotion, KeepTheirOwnFrameAndMatchTheReference) {
    Settings settings = lockstepSettings({GetParam().pipeline, Mode::Reliable, Backend::Compute, 64});
    settings.gpuLevels = GetParam().levels;
    CULLIDE_GPU_CULLER_OR_SKIP(unkeyed, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    InstanceScene scene = randomInstances(11, 24, true, 6);
    std::vector<std::uint64_t> version(scene.meshes.size(), 1);
    std::size_t pairs = 0, groupsKept = 0;
    for (int frame = 0; frame < 5; ++frame) {
        std::vector<Object> objects = scene.instances();
        std::size_t ofChangedMesh = 0;
        for (std::size_t i = 0; i < objects.size(); ++i) {
            objects[i].staticKey = i + 1;
            objects[i].version = version[scene.meshOf[i]];
            ofChangedMesh += frame == 3 && scene.meshOf[i] == 0 ? 1 : 0;
        }
        Result got, plain;
        const Comparison c = runAndCompare(*culler, *reference, objects, got);
        EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << frame;
        unkeyed->run(scene.instances(), plain);
        EXPECT_EQ(trianglePairs(got), trianglePairs(plain)) << frame;
        // The paper's pipeline takes exact group boxes as its items' boxes: the same sets as without keys.
        if (GetParam().pipeline == Pipeline::Paper) {
            EXPECT_EQ(pcsTriangles(got), pcsTriangles(plain)) << frame;
        }
        EXPECT_EQ(got.stats.movingObjectsReused, frame == 0 ? 0u : objects.size() - ofChangedMesh) << frame;
        pairs += c.expected;
        groupsKept += got.stats.prepassGroupsOut;
        for (Transform& t : scene.transforms) {
            t.translation += Vec3(0.011, -0.007, 0.005);
            t.linear = Eigen::AngleAxisd(0.03, Vec3(0.3, 1.0, -0.2).normalized()).toRotationMatrix() * t.linear;
        }
        if (frame == 2) {  // a shared mesh deforms in its own frame, and says so
            for (Vec3& v : scene.meshes[0].vertices) v = Vec3(1.2 * v.x(), v.y(), 0.8 * v.z());
            ++version[0];
        }
        scene.refreshWorldMeshes();
    }
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GT(pairs, 20u) << "too sparse to test anything";
    if (GetParam().levels == GpuLevels::Always) {
        EXPECT_GT(log->itemsPruned, 0u) << log->summary();
        EXPECT_GT(groupsKept, 0u);
    }
}

INSTANTIATE_TEST_SUITE_P(Pipelines, KeyedInstancesInMotion,
                         ::testing::Values(Case{GpuLevels::Never, Pipeline::Auto},
                                           Case{GpuLevels::Always, Pipeline::Auto},
                                           Case{GpuLevels::Always, Pipeline::Paper}));

// A moving keyed mesh that changes in its own frame (a new version) gets its own-frame group boxes again: kept ones
// would let the CPU's box pre-pass drop the groups that now reach another object.
TEST(KeyedInstancesInMotion, AVersionChangeRecomputesTheOwnFrameGroupBoxes) {
    Settings settings = withLevels(GpuLevels::Always, Pipeline::Auto);
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    auto reference = createReferenceCuller(settings);
    TriangleMesh sphere = scenes::makeSphere(1.0, 32, 16);
    // A slab in a corner of the sphere's box, outside the sphere until the sphere moves in its own frame.
    TriangleMesh slab = scenes::makeBox(Vec3(0.1, 0.2, 0.2));
    for (Vec3& v : slab.vertices) v += Vec3(1.05, 0.8, 0.8);
    Transform t;
    std::size_t pairsAfter = 0;
    for (int frame = 0; frame < 4; ++frame) {
        if (frame == 2)
            for (Vec3& v : sphere.vertices) v += Vec3(0.3, 0.3, 0.3);
        t.translation = Vec3(0.0, 1e-3 * frame, 0.0);  // it moves every frame
        Object body;
        body.mesh = &sphere;
        body.transform = &t;
        body.staticKey = 1;
        body.version = frame < 2 ? 1 : 2;
        Object other;
        other.mesh = &slab;
        const std::vector<Object> objects = {body, other};
        Result got;
        const Comparison c = runAndCompare(*culler, *reference, objects, got);
        EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
        EXPECT_EQ(got.stats.movingObjectsReused, frame == 1 || frame == 3 ? 1u : 0u) << frame;
        if (frame >= 2) pairsAfter += c.expected;
    }
    EXPECT_GT(pairsAfter, 0u) << "the sphere must reach the slab";
}

// A keyed mesh that rests, moves and rests at its new place, beside a static ground that keeps the device's resident
// region where it is: when it rests again, its boxes, tree and place in the region are those of the new place.
class KeyedMeshAtRest : public ::testing::TestWithParam<GpuLevels> {};

TEST_P(KeyedMeshAtRest, GetsItsWorldPartAgainAfterMoving) {
    Settings settings = withLevels(GetParam(), Pipeline::Auto);
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    auto reference = createReferenceCuller(settings);
    const TriangleMesh sphere = scenes::makeSphere(1.0, 32, 16);
    TriangleMesh slab = scenes::makeBox(Vec3(0.2, 0.2, 0.2));
    for (Vec3& v : slab.vertices) v += Vec3(1.3, 0.0, 0.0);
    TriangleMesh ground = scenes::makeBox(Vec3(10.0, 10.0, 0.2));
    for (Vec3& v : ground.vertices) v += Vec3(0.0, 0.0, -0.95);
    Transform t;
    std::size_t pairs = 0, reused = 0;
    for (int frame = 0; frame < 6; ++frame) {
        t.translation = Vec3(frame < 2 ? 0.0 : 0.5, 0.0, 0.0);  // rests, moves once, rests at the new place
        Object body;
        body.mesh = &sphere;
        body.transform = &t;
        body.staticKey = 1;
        body.version = 1;
        Object other;
        other.mesh = &slab;
        Object floor;
        floor.mesh = &ground;
        floor.staticKey = 2;
        floor.version = 1;
        Result got;
        const Comparison c = runAndCompare(*culler, *reference, {body, other, floor}, got);
        EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
        EXPECT_EQ(c.missed, 0u) << "frame " << frame << ": " << c.firstMissed;
        EXPECT_EQ(c.spurious, 0u) << frame;
        pairs += c.expected;
        reused += got.stats.staticObjectsReused;
    }
    EXPECT_GT(pairs, 0u);
    EXPECT_GE(reused, 7u) << "the ground from its second frame, the body at rest";
}

INSTANTIATE_TEST_SUITE_P(Levels, KeyedMeshAtRest, ::testing::Values(GpuLevels::Never, GpuLevels::Always));

}  // namespace
}  // namespace cullide::test
