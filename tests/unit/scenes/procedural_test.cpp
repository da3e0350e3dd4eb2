// Procedural meshes (Procedural.h): counts, orientation and volume of tori, spheres, open cylinders and boxes, and
// invalid parameters rejected.
#include "MeshChecks.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cullide::scenes {
namespace {

using namespace cullide::test;

TEST(Procedural, TorusCountsOrientationAndVolume) {
    const TriangleMesh t = makeTorus(1.0, 0.3, 40, 20);
    EXPECT_EQ(t.vertices.size(), 800u);
    EXPECT_EQ(t.triangles.size(), 1600u);
    EXPECT_TRUE(isClosedOriented(t));
    EXPECT_NEAR(signedVolume(t), 2.0 * kPi * kPi * 1.0 * 0.09, 0.03 * 1.78);
}

TEST(Procedural, SphereCountsOrientationAndVolume) {
    const TriangleMesh s = makeSphere(1.0, 32, 16);
    EXPECT_EQ(s.triangles.size(), 2u * 32u * 15u);
    EXPECT_EQ(s.vertices.size(), 2u + 32u * 15u);
    EXPECT_TRUE(isClosedOriented(s));
    EXPECT_NEAR(signedVolume(s), 4.0 / 3.0 * kPi, 0.04 * 4.19);
    EXPECT_TRUE(isClosedOriented(makeSphere(0.5, 3, 2)));  // the smallest: a double pyramid
}

TEST(Procedural, OpenCylinderAndBox) {
    const TriangleMesh c = makeOpenCylinder(0.5, 2.0, 12, 4);
    EXPECT_EQ(c.triangles.size(), 2u * 12u * 4u);
    EXPECT_EQ(c.vertices.size(), 12u * 5u);
    const auto edges = directedEdges(c);
    const auto boundary = std::count_if(edges.begin(), edges.end(), [&](const auto& e) {
        return edges.count({e.first.second, e.first.first}) == 0;
    });
    EXPECT_EQ(boundary, 24);
    // Prism over a regular 12-gon: (n/2) r^2 sin(2 pi / n) h.
    EXPECT_NEAR(cappedVolume(c), 0.5 * 12 * 0.25 * std::sin(2 * kPi / 12) * 2.0, 1e-9);
    const Aabb cb = boundsOf(c);
    EXPECT_NEAR(cb.min.z(), -1.0, 1e-12);
    EXPECT_NEAR(cb.max.z(), 1.0, 1e-12);

    TriangleMesh b = makeBox(Vec3(1, 2, 3));
    EXPECT_EQ(b.triangles.size(), 12u);
    EXPECT_TRUE(isClosedOriented(b));
    EXPECT_NEAR(signedVolume(b), 48.0, 1e-12);
    transformMesh(b, Eigen::Affine3d(Eigen::Translation3d(10, 0, 0)));
    const Aabb bb = boundsOf(b);
    EXPECT_EQ(bb.min, Vec3(9, -2, -3));
    EXPECT_EQ(bb.max, Vec3(11, 2, 3));
    EXPECT_TRUE(boundsOf(TriangleMesh{}).isEmpty());
}

TEST(Procedural, RejectsInvalidParameters) {
    EXPECT_THROW(makeTorus(1, 0.3, 2, 10), std::invalid_argument);
    EXPECT_THROW(makeTorus(1, -0.3, 10, 10), std::invalid_argument);
    EXPECT_THROW(makeOpenCylinder(1, 1, 3, 0), std::invalid_argument);
    EXPECT_THROW(makeSphere(std::nan(""), 8, 8), std::invalid_argument);
    EXPECT_THROW(makeBox(Vec3(1, -1, 1)), std::invalid_argument);
}

}  // namespace
}  // namespace cullide::scenes
