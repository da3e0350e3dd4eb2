// Fracture geometry (Fracture.h): Voronoi cuts keep every bit of surface (gap 0), pieces stay inside their cells
// and apart (gap > 0), deterministic for a seed, bad input skipped or rejected. No GL.
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

}  // namespace
}  // namespace cullide::demo
