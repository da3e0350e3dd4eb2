// Fracture geometry: Voronoi cuts keep every bit of surface (gap 0), pieces stay inside their cells and apart
// (gap > 0), mass properties of known solids are exact. No GL.
#include "cullide/demo/Fracture.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace cullide::demo {
namespace {

double area(const TriangleMesh& m) {
    double a = 0;
    for (const auto& t : m.triangles)
        a += 0.5 * (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).norm();
    return a;
}

std::size_t nearestSite(const std::vector<Vec3>& sites, const Vec3& p) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < sites.size(); ++i)
        if ((p - sites[i]).squaredNorm() < (p - sites[best]).squaredNorm()) best = i;
    return best;
}

TEST(Fracture, CutWithoutGapKeepsTheWholeSurface) {
    const TriangleMesh sphere = scenes::makeSphere(1.0, 48, 24);
    const auto sites = fractureSites(scenes::boundsOf(sphere), Vec3(0.9, 0.1, 0), 12, 7);
    const auto pieces = voronoiCut(sphere, sites, 0.0);
    ASSERT_EQ(pieces.size(), sites.size());
    double total = 0;
    std::size_t nonEmpty = 0;
    for (const auto& p : pieces) {
        total += area(p);
        nonEmpty += p.triangles.empty() ? 0 : 1;
    }
    EXPECT_NEAR(total, area(sphere), 1e-9 * area(sphere));
    EXPECT_GE(nonEmpty, 4u) << "a 12-site cut of a sphere must give several pieces";
}

TEST(Fracture, PiecesLieInTheirCellsAndStartApart) {
    const TriangleMesh torus = scenes::makeTorus(1.0, 0.3, 64, 24);
    const auto sites = fractureSites(scenes::boundsOf(torus), Vec3(1.3, 0, 0), 10, 3);
    const double gap = 0.02;
    const auto pieces = voronoiCut(torus, sites, gap);
    for (std::size_t i = 0; i < pieces.size(); ++i)
        for (const Vec3& v : pieces[i].vertices) {
            EXPECT_EQ(nearestSite(sites, v), i);
            // At least gap/2 from every bisector: |v - s_j| - |v - s_i| measured along the bisector normal.
            for (std::size_t j = 0; j < sites.size(); ++j) {
                if (j == i) continue;
                const Vec3 n = (sites[j] - sites[i]).normalized();
                const double d = n.dot(0.5 * (sites[i] + sites[j])) - n.dot(v);
                EXPECT_GE(d, 0.5 * gap - 1e-9);
            }
        }
    double total = 0;
    for (const auto& p : pieces) total += area(p);
    EXPECT_LT(total, area(torus));
    EXPECT_GT(total, 0.8 * area(torus)) << "a thin gap removes only a thin band";
}

TEST(Fracture, DeterministicForASeedAndDifferentAcrossSeeds) {
    const Aabb box{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
    EXPECT_EQ(fractureSites(box, Vec3(0, 1, 0), 9, 42), fractureSites(box, Vec3(0, 1, 0), 9, 42));
    EXPECT_NE(fractureSites(box, Vec3(0, 1, 0), 9, 42), fractureSites(box, Vec3(0, 1, 0), 9, 43));
}

TEST(Fracture, BadInputIsSkippedOrRejected) {
    TriangleMesh m = scenes::makeBox(Vec3(1, 1, 1));
    m.vertices.push_back(Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0));
    m.triangles.push_back({0, 1, static_cast<std::uint32_t>(m.vertices.size() - 1)});  // non-finite vertex
    m.triangles.push_back({0, 1, 1000});                                                 // out of range
    const auto pieces = voronoiCut(m, {Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0)}, 0.0);
    double total = 0;
    for (const auto& p : pieces) total += area(p);
    EXPECT_NEAR(total, 24.0, 1e-9);  // the box's six faces, nothing else
    EXPECT_EQ(voronoiCut(m, {}, 0.0).size(), 0u);
    EXPECT_THROW(voronoiCut(m, {Vec3(0, 0, 0)}, -1.0), std::invalid_argument);
    EXPECT_THROW(voronoiCut(m, {Vec3(0, std::nan(""), 0)}, 0.0), std::invalid_argument);
    EXPECT_THROW(fractureSites(Aabb{}, Vec3::Zero(), 3, 1), std::invalid_argument);
    EXPECT_THROW(fractureSites(Aabb{Vec3::Zero(), Vec3::Ones()}, Vec3::Zero(), 0, 1), std::invalid_argument);
}

TEST(Fracture, DuplicateSitesGiveOnePiece) {
    const TriangleMesh m = scenes::makeSphere(1.0, 16, 8);
    const auto pieces = voronoiCut(m, {Vec3(0, 0, 0), Vec3(0, 0, 0)}, 0.0);
    EXPECT_NEAR(area(pieces[0]) + area(pieces[1]), area(m), 1e-9);
    EXPECT_TRUE(pieces[1].triangles.empty());
}

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
