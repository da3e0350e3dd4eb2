// Mass properties of convex hulls (Fracture.h): exact for known solids (a rotated box, an off-centre tetrahedron),
// a thin box for flat point sets. No GL.
#include "cullide/demo/Fracture.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace cullide::demo {
namespace {

TEST(MassProperties, BoxIsExact) {
    // A 2 x 4 x 6 box rotated and moved: volume 48, inertia m/12 (b^2 + c^2) etc. about its centre.
    TriangleMesh box = scenes::makeBox(Vec3(1, 2, 3));
    const Eigen::Affine3d pose = Eigen::Translation3d(5, -2, 1) * Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized());
    scenes::transformMesh(box, pose);
    const MassProperties m = hullMassProperties(box.vertices, 2.0, 1e-3);
    ASSERT_TRUE(m.fromHull);
    EXPECT_NEAR(m.volume, 48.0, 1e-4);
    EXPECT_NEAR(m.mass, 96.0, 2e-4);
    EXPECT_LT((m.centre - Vec3(5, -2, 1)).norm(), 1e-5);
    const double k = 96.0 / 12.0;
    EXPECT_NEAR(m.inertia[0], k * (4 + 16), 1e-2);  // eigenvalues ascending: about the longest axis first
    EXPECT_NEAR(m.inertia[1], k * (4 + 36), 1e-2);
    EXPECT_NEAR(m.inertia[2], k * (16 + 36), 1e-2);
    EXPECT_NEAR(m.axes.determinant(), 1.0, 1e-9);
    // The principal axis of the smallest moment is the box's 6-long axis (local z), rotated.
    const Vec3 longAxis = pose.linear() * Vec3::UnitZ();
    EXPECT_NEAR(std::fabs(m.axes.col(0).dot(longAxis)), 1.0, 1e-6);
}

TEST(MassProperties, OffCentreTetrahedronIsExact) {
    // Tetrahedron (0, a e1, a e2, a e3) moved by t: volume a^3/6, centre t + a/4 (1,1,1), inertia about the centre
    // from the known second moments (a^5/60 on the diagonal of the covariance, a^5/120 off it, about the origin).
    const double a = 2.0, density = 3.0;
    const Vec3 t(10, -4, 7);
    const std::vector<Vec3> points = {t, t + Vec3(a, 0, 0), t + Vec3(0, a, 0), t + Vec3(0, 0, a)};
    const MassProperties m = hullMassProperties(points, density, 1e-3);
    ASSERT_TRUE(m.fromHull);
    const double volume = a * a * a / 6.0;
    EXPECT_NEAR(m.volume, volume, 1e-12);
    EXPECT_NEAR(m.mass, density * volume, 1e-12);
    EXPECT_LT((m.centre - (t + Vec3::Constant(a / 4))).norm(), 1e-12);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Constant(std::pow(a, 5) / 120.0);
    cov.diagonal().setConstant(std::pow(a, 5) / 60.0);
    const Vec3 c = Vec3::Constant(a / 4);
    const Eigen::Matrix3d central = density * (cov - volume * c * c.transpose());
    const Eigen::Matrix3d inertia = central.trace() * Eigen::Matrix3d::Identity() - central;
    const Eigen::Matrix3d got = m.axes * m.inertia.asDiagonal() * m.axes.transpose();
    EXPECT_LT((got - inertia).norm(), 1e-9 * inertia.norm());
    EXPECT_THROW(hullMassProperties(points, density, 0.0), std::invalid_argument);
    EXPECT_THROW(hullMassProperties(points, density, std::nan("")), std::invalid_argument);
}

TEST(MassProperties, FlatPointSetsFallBackToAThinBox) {
    const std::vector<Vec3> flat = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
    const MassProperties m = hullMassProperties(flat, 1.0, 0.01);
    EXPECT_FALSE(m.fromHull);
    EXPECT_NEAR(m.volume, 0.01, 1e-12);
    EXPECT_GT(m.inertia.minCoeff(), 0.0);
    EXPECT_THROW(hullMassProperties({}, 1.0, 0.01), std::invalid_argument);
    EXPECT_THROW(hullMassProperties(flat, 0.0, 0.01), std::invalid_argument);
}

}  // namespace
}  // namespace cullide::demo
