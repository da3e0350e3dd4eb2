// Objects as a shared local mesh plus a transform (Object::transform): the conservative world box, the documented
// rounding, and the reference culler's results against world-space twins (no GL needed).
#include "Compare.h"
#include "Instances.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>

namespace cullide {
Aabb transformedBounds(const Transform& t, const Aabb& local);  // plugin/src/WorldMeshes.h (internal)
}

namespace cullide::test {
namespace {

TEST(Transform, PointIsRoundedInTheDocumentedOrder) {
    Transform t;
    t.linear << 0.1, 0.2, 0.3, -1e16, 1.0, 1e16, 1, 1, 1;
    t.translation = Vec3(0.7, 1.0, -3.0);
    const Vec3 p(1.0 / 3, 7.0, 1e-9);
    const Vec3 w = transformPoint(t, p);
    for (int i = 0; i < 3; ++i) {
        volatile double x = t.linear(i, 0) * p[0];  // one rounding per operation, in the documented order
        volatile double y = t.linear(i, 1) * p[1];
        x = x + y;
        y = t.linear(i, 2) * p[2];
        x = x + y;
        x = x + t.translation[i];
        EXPECT_EQ(w[i], x) << "coordinate " << i;
    }
}

// Every transformed point of a box lies in transformedBounds, rounding included (transformPoint is monotone in each
// coordinate), and the bounds are tight (each is attained by a corner): corners, edge, face and inner points of
// boxes at every magnitude, under rotations, scalings and shears with mixed signs.
TEST(Transform, BoundsHoldEveryTransformedPointAndAreTight) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::size_t checked = 0;
    for (const double magnitude : {1e-300, 1e-12, 1.0, 1e3, 1e12, 1e100, 1e250}) {
        for (int trial = 0; trial < 200; ++trial) {
            Transform t;
            t.linear = Eigen::Quaterniond(Eigen::Vector4d(unit(rng), unit(rng), unit(rng), unit(rng)).normalized())
                           .toRotationMatrix();
            if (trial % 3 == 1) t.linear(0, 1) += 0.37 * unit(rng);
            if (trial % 3 == 2) t.linear *= 1e-3 + std::abs(unit(rng)) * 1e3;
            if (trial % 7 == 3) t.linear(1, 2) = 1e-17 * unit(rng);  // nearly axis-aligned edges
            t.translation = Vec3(unit(rng), unit(rng), unit(rng)) * magnitude * (trial % 2 ? 1.0 : 1e-4);
            Aabb local;
            local.grow(Vec3(unit(rng), unit(rng), unit(rng)) * magnitude);
            local.grow(Vec3(unit(rng), unit(rng), unit(rng)) * magnitude);
            const Aabb world = transformedBounds(t, local);
            ASSERT_TRUE(world.isFinite());
            Aabb corners;
            for (int sample = 0; sample < 64; ++sample) {
                Vec3 p;
                for (int k = 0; k < 3; ++k) {
                    // Corners (sample < 8), then points with one, two or three free coordinates.
                    const bool free = sample >= 8 && ((sample >> k) & 1) != 0;
                    const double f = free ? 0.5 * (1 + unit(rng)) : ((sample >> (k + 3)) & 1 ? 1.0 : 0.0);
                    p[k] = sample < 8 ? ((sample >> k) & 1 ? local.max[k] : local.min[k])
                                      : local.min[k] + f * (local.max[k] - local.min[k]);
                    p[k] = std::min(std::max(p[k], local.min[k]), local.max[k]);
                }
                const Vec3 w = transformPoint(t, p);
                if (sample < 8) corners.grow(w);
                ASSERT_TRUE((w.array() >= world.min.array()).all() && (w.array() <= world.max.array()).all())
                    << "magnitude " << magnitude << " trial " << trial << " sample " << sample;
                ++checked;
            }
            EXPECT_EQ(world.min, corners.min) << "not tight: magnitude " << magnitude << " trial " << trial;
            EXPECT_EQ(world.max, corners.max) << "not tight: magnitude " << magnitude << " trial " << trial;
        }
    }
    EXPECT_EQ(checked, 7u * 200 * 64);
}

TEST(Transform, ReferenceCullerAgreesWithWorldSpaceTwins) {
    auto reference = createReferenceCuller(Settings{});
    std::size_t pairs = 0;
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
        const InstanceScene scene = randomInstances(seed, 24, seed % 2 == 0, 5);
        Result twins, instances;
        reference->run(scene.worldObjects(), twins);
        reference->run(scene.instances(), instances);
        EXPECT_EQ(trianglePairs(instances), trianglePairs(twins)) << "seed " << seed;
        EXPECT_EQ(instances.pcs, twins.pcs);
        EXPECT_EQ(instances.pcsTriangles, twins.pcsTriangles);
        pairs += trianglePairs(twins).size();
    }
    EXPECT_GT(pairs, 50u) << "scenes too sparse to test anything";
}

TEST(Transform, BadTransformsAreRejectedAndHarmNoOne) {
    const InstanceScene scene = randomInstances(3, 6, false);
    std::vector<Object> objects = scene.instances();
    Transform nan = scene.transforms[1];
    nan.linear(1, 2) = std::numeric_limits<double>::quiet_NaN();
    Transform huge;
    huge.linear *= 1e308;  // (2, 1, 1) lands at 2e308: beyond the double range
    TriangleMesh triangle;
    triangle.vertices = {{1, 1, 1}, {2, 1, 1}, {1, 2, 1}};
    triangle.triangles = {{0, 1, 2}};
    objects[1].transform = &nan;
    objects[2].mesh = &triangle;
    objects[2].transform = &huge;
    Result got, expected;
    auto reference = createReferenceCuller(Settings{});
    reference->run(objects, got);
    ASSERT_EQ(got.rejected.size(), 2u);
    EXPECT_EQ(got.rejected[0].object, 1u);
    EXPECT_NE(got.rejected[0].message.find("non-finite"), std::string::npos) << got.rejected[0].message;
    EXPECT_EQ(got.rejected[1].object, 2u);
    EXPECT_NE(got.rejected[1].message.find("double range"), std::string::npos) << got.rejected[1].message;
    // The valid ones get exactly what they get without the bad ones around.
    std::vector<Object> valid = scene.instances();
    valid[1] = Object{};
    valid[1].box = Aabb{Vec3::Constant(1e9), Vec3::Constant(1e9 + 1)};
    valid[2] = valid[1];
    reference->run(valid, expected);
    EXPECT_EQ(trianglePairs(got), trianglePairs(expected));
}

}  // namespace
}  // namespace cullide::test
