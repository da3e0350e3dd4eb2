// Procedural meshes, the paper's environments and the random scenes: counts, orientation, density, determinism,
// deformation and that objects really intersect where the scene promises it.
#include "cullide/TriangleTest.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

namespace cullide::scenes {
namespace {

constexpr double kPi = 3.1415926535897932384626433832795;

// ---------------------------------------------------------------------------------------------------------------
// Geometry helpers (independent of the code under test)

using Edge = std::pair<std::uint32_t, std::uint32_t>;

std::map<Edge, int> directedEdges(const TriangleMesh& m) {
    std::map<Edge, int> edges;
    for (const auto& t : m.triangles) {
        for (int k = 0; k < 3; ++k) ++edges[{t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]}];
    }
    return edges;
}

/// Closed, consistently oriented 2-manifold: every directed edge once, its reverse once.
::testing::AssertionResult isClosedOriented(const TriangleMesh& m) {
    const auto edges = directedEdges(m);
    for (const auto& [e, n] : edges) {
        if (n != 1) return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " used " << n;
        if (edges.count({e.second, e.first}) != 1) {
            return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " has no twin";
        }
    }
    return ::testing::AssertionSuccess();
}

double det(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

double signedVolume(const TriangleMesh& m) {
    double v = 0.0;
    for (const auto& t : m.triangles) v += det(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
    return v / 6.0;
}

/// Volume of an oriented mesh whose boundary loops are closed by fans from each loop's centroid (open cylinders).
double cappedVolume(const TriangleMesh& m) {
    const auto edges = directedEdges(m);
    std::vector<Edge> boundary;
    for (const auto& [e, n] : edges) {
        if (edges.count({e.second, e.first}) == 0) boundary.push_back(e);
    }
    // Union-find over boundary vertices: one component per loop.
    std::vector<std::uint32_t> parent(m.vertices.size());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](std::uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (const Edge& e : boundary) parent[find(e.first)] = find(e.second);
    std::map<std::uint32_t, std::pair<Vec3, int>> centroid;
    for (const Edge& e : boundary) {
        auto& c = centroid.try_emplace(find(e.first), Vec3::Zero(), 0).first->second;
        c.first += m.vertices[e.first];
        ++c.second;
    }
    double v = signedVolume(m) * 6.0;
    for (const Edge& e : boundary) {
        const auto& c = centroid.at(find(e.first));
        v += det(m.vertices[e.second], m.vertices[e.first], c.first / c.second);
    }
    return v / 6.0;
}

Aabb triangleBox(const TriangleMesh& m, const TriangleIndices& t) {
    Aabb b;
    for (const auto i : t) b.grow(m.vertices[i]);
    return b;
}

/// True iff some triangle of `a` intersects some triangle of `b` (uniform grid over the boxes' overlap).
bool anyIntersection(const TriangleMesh& a, const TriangleMesh& b) {
    const Aabb ba = boundsOf(a), bb = boundsOf(b);
    if (!ba.overlaps(bb)) return false;
    const Aabb region{ba.min.cwiseMax(bb.min), ba.max.cwiseMin(bb.max)};
    std::vector<std::pair<Aabb, std::uint32_t>> candidates;
    double extentSum = 0.0;
    for (std::uint32_t i = 0; i < b.triangles.size(); ++i) {
        const Aabb box = triangleBox(b, b.triangles[i]);
        if (box.overlaps(region)) {
            candidates.emplace_back(box, i);
            extentSum += box.extent().maxCoeff();
        }
    }
    if (candidates.empty()) return false;
    const double cell = std::max({extentSum / static_cast<double>(candidates.size()), region.extent().maxCoeff() / 32.0, 1e-12});
    Eigen::Vector3i dims;
    for (int k = 0; k < 3; ++k) dims[k] = static_cast<int>(region.extent()[k] / cell) + 1;
    auto cellRange = [&](const Aabb& box, Eigen::Vector3i& lo, Eigen::Vector3i& hi) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::clamp(static_cast<int>(std::floor((box.min[k] - region.min[k]) / cell)), 0, dims[k] - 1);
            hi[k] = std::clamp(static_cast<int>(std::floor((box.max[k] - region.min[k]) / cell)), 0, dims[k] - 1);
        }
    };
    std::vector<std::vector<std::uint32_t>> grid(static_cast<std::size_t>(dims.prod()));
    auto at = [&](int x, int y, int z) -> std::vector<std::uint32_t>& {
        return grid[static_cast<std::size_t>((z * dims[1] + y) * dims[0] + x)];
    };
    for (std::uint32_t c = 0; c < candidates.size(); ++c) {
        Eigen::Vector3i lo, hi;
        cellRange(candidates[c].first, lo, hi);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x) at(x, y, z).push_back(c);
    }
    for (const auto& ta : a.triangles) {
        const Aabb box = triangleBox(a, ta);
        if (!box.overlaps(region)) continue;
        Eigen::Vector3i lo, hi;
        cellRange(box, lo, hi);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    for (const std::uint32_t c : at(x, y, z)) {
                        if (!candidates[c].first.overlaps(box)) continue;
                        const auto& tb = b.triangles[candidates[c].second];
                        if (trianglesIntersect(a.vertices[ta[0]], a.vertices[ta[1]], a.vertices[ta[2]],
                                               b.vertices[tb[0]], b.vertices[tb[1]], b.vertices[tb[2]])) {
                            return true;
                        }
                    }
    }
    return false;
}

bool sameMeshes(const std::vector<TriangleMesh>& x, const std::vector<TriangleMesh>& y) {
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (x[i].vertices != y[i].vertices || x[i].triangles != y[i].triangles) return false;
    }
    return true;
}

/// Relative change of a few vertex-to-vertex distances: zero for rigid motions.
double shapeChange(const TriangleMesh& p, const TriangleMesh& q) {
    double worst = 0.0;
    const std::size_t n = p.vertices.size();
    for (std::size_t k = 0; k < 16; ++k) {
        const std::size_t i = (k * 7919) % n, j = (k * 104729 + n / 2) % n;
        const double dp = (p.vertices[i] - p.vertices[j]).norm(), dq = (q.vertices[i] - q.vertices[j]).norm();
        if (dp > 0.0) worst = std::max(worst, std::abs(dp - dq) / dp);
    }
    return worst;
}

// ---------------------------------------------------------------------------------------------------------------
// Procedural meshes

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

// ---------------------------------------------------------------------------------------------------------------
// Environment 1

TEST(Env1, CountsDensityAndContainment) {
    auto env = makeEnv1(42);
    EXPECT_FALSE(env->name().empty());
    for (const int f : {0, 17, 100, 250, 1000}) {
        SCOPED_TRACE(f);
        const auto& meshes = env->frame(f);
        ASSERT_EQ(meshes.size(), 100u);
        double volume = 0.0;
        for (const TriangleMesh& m : meshes) {
            EXPECT_EQ(m.triangles.size(), 200u);
            volume += cappedVolume(m);
            const Aabb b = boundsOf(m);
            EXPECT_TRUE((b.min.array() >= -1e-9).all() && (b.max.array() <= 1.0 + 1e-9).all());
        }
        // The unit cube has volume 1: the solid volume is the density.
        EXPECT_GE(volume, 0.05);
        EXPECT_LE(volume, 0.06);
    }
}

TEST(Env1, DeterministicForASeedAndFramesInAnyOrder) {
    auto a = makeEnv1(7, 20, 100);
    auto b = makeEnv1(7, 20, 100);
    auto c = makeEnv1(8, 20, 100);
    const std::vector<TriangleMesh> a10 = a->frame(10);
    EXPECT_TRUE(sameMeshes(a10, b->frame(10)));
    EXPECT_FALSE(sameMeshes(a10, c->frame(10)));
    a->frame(3);
    a->frame(500);
    EXPECT_TRUE(sameMeshes(a10, a->frame(10)));
    for (const auto& m : a10) EXPECT_NEAR(static_cast<double>(m.triangles.size()), 100.0, 10.0);
}

TEST(Env1, CylindersMoveAndDeformEveryFrame) {
    auto env = makeEnv1(3, 30);
    const std::vector<TriangleMesh> f0 = env->frame(0);
    const std::vector<TriangleMesh> f1 = env->frame(1);
    const std::vector<TriangleMesh> f20 = env->frame(20);
    for (std::size_t i = 0; i < f0.size(); ++i) {
        for (std::size_t k = 0; k < f0[i].vertices.size(); ++k) {
            ASSERT_NE(f0[i].vertices[k], f1[i].vertices[k]) << "object " << i << " vertex " << k;
        }
        EXPECT_GT(shapeChange(f0[i], f20[i]), 1e-3) << "object " << i << " only moved rigidly";
        EXPECT_GT((boundsOf(f0[i]).min - boundsOf(f20[i]).min).norm(), 1e-3) << "object " << i << " did not move";
    }
}

TEST(Env1, ObjectsOverlapSometimes) {
    auto env = makeEnv1(11);
    int framesWithContact = 0, contacts = 0;
    for (int f = 0; f < 300; f += 30) {
        const auto& meshes = env->frame(f);
        std::vector<Aabb> boxes;
        for (const auto& m : meshes) boxes.push_back(boundsOf(m));
        int here = 0;
        for (std::size_t i = 0; i < meshes.size(); ++i)
            for (std::size_t j = i + 1; j < meshes.size(); ++j)
                if (boxes[i].overlaps(boxes[j]) && anyIntersection(meshes[i], meshes[j])) ++here;
        contacts += here;
        framesWithContact += here > 0 ? 1 : 0;
        // "Sometimes": at 5.5% density random placement makes each cylinder touch about one other on average
        // (~20-70 of the 4950 pairs); nearly all pairs are apart.
        EXPECT_LT(here, 99) << "frame " << f;
    }
    std::printf("env1: %d of 10 frames with contact, %.1f intersecting pairs per frame\n", framesWithContact,
                contacts / 10.0);
    EXPECT_GE(framesWithContact, 3);
    EXPECT_GT(contacts, 0);
}

// ---------------------------------------------------------------------------------------------------------------
// Environment 2

TEST(Env2, ToriCountsOrientationDeformationAndDeterminism) {
    auto env = makeEnv2(42);
    const std::vector<TriangleMesh> f0 = env->frame(0);
    ASSERT_EQ(f0.size(), 6u);
    for (const TriangleMesh& m : f0) {
        EXPECT_NEAR(static_cast<double>(m.triangles.size()), 20000.0, 200.0);
        EXPECT_TRUE(isClosedOriented(m));
        EXPECT_GT(signedVolume(m), 0.0);
    }
    const std::vector<TriangleMesh> f1 = env->frame(1);
    const std::vector<TriangleMesh> f15 = env->frame(15);
    for (std::size_t i = 0; i < f0.size(); ++i) {
        EXPECT_NE(f0[i].vertices, f1[i].vertices);
        EXPECT_GT(shapeChange(f0[i], f15[i]), 1e-3) << "torus " << i << " only moved rigidly";
    }
    EXPECT_TRUE(sameMeshes(f15, makeEnv2(42)->frame(15)));
    EXPECT_FALSE(sameMeshes(f15, makeEnv2(43)->frame(15)));
}

TEST(Env2, DensityAndOccasionalCollisions) {
    auto env = makeEnv2(5, 6, 4000);  // fewer triangles keep the intersection checks quick
    Aabb all;
    double volume = 0.0;
    int framesWithContact = 0, contactPairs = 0;
    const int frames = 40;
    for (int f = 0; f < frames * 15; f += 15) {
        const auto& meshes = env->frame(f);
        double v = 0.0;
        for (const auto& m : meshes) {
            v += signedVolume(m);
            all.grow(boundsOf(m));
        }
        volume += v / frames;
        int here = 0;
        for (std::size_t i = 0; i < meshes.size(); ++i)
            for (std::size_t j = i + 1; j < meshes.size(); ++j) here += anyIntersection(meshes[i], meshes[j]) ? 1 : 0;
        framesWithContact += here > 0 ? 1 : 0;
        contactPairs += here;
    }
    // The tori stay in a cube of side L; the region they sweep is at most that cube, so this ratio is an upper
    // estimate of the 6-8% density: it is at least the density and close to it once the walls are reached.
    const double swept = all.extent().prod();
    EXPECT_GE(volume / swept, 0.06);
    EXPECT_LE(volume / swept, 0.12);
    // Colliding sometimes: contacts happen, but most of the 15 pairs are apart at any time.
    std::printf("env2: %d of %d frames with contact, %.2f pairs per frame\n", framesWithContact, frames,
                static_cast<double>(contactPairs) / frames);
    EXPECT_GE(framesWithContact, 2);
    EXPECT_LT(contactPairs, frames * 15 / 2);
}

// ---------------------------------------------------------------------------------------------------------------
// Environment 3

void checkEnv3(Environment& env, std::size_t bunnyTriangles, std::size_t dragonTriangles) {
    const std::vector<TriangleMesh> f0 = env.frame(0);
    ASSERT_EQ(f0.size(), 2u);
    EXPECT_EQ(f0[0].triangles.size(), bunnyTriangles);
    EXPECT_EQ(f0[1].triangles.size(), dragonTriangles);
    for (const auto& m : f0) {
        const double size = boundsOf(m).extent().maxCoeff();
        EXPECT_GT(size, 0.6);
        EXPECT_LT(size, 1.3);
    }
    int intersecting = 0, sampled = 0;
    for (int f = 0; f < 240; f += 10, ++sampled) {
        const auto& meshes = env.frame(f);
        if (anyIntersection(meshes[0], meshes[1])) ++intersecting;
    }
    std::printf("env3: %d of %d sampled frames interpenetrate\n", intersecting, sampled);
    EXPECT_GE(intersecting, sampled * 3 / 4) << intersecting << " of " << sampled << " frames interpenetrate";
}

TEST(Env3, StandInsWhenTheDataDirectoryIsMissing) {
    for (const std::string& dir : {std::string(), std::string("/nonexistent/cullide/data")}) {
        SCOPED_TRACE(dir);
        bool standIns = false;
        auto env = makeEnv3(dir, false, &standIns);
        EXPECT_TRUE(standIns);
        checkEnv3(*env, 75076, 19992);
    }
    EXPECT_NO_THROW(makeEnv3("", true, nullptr));
}

TEST(Env3, RigidBunnyStaticDragonAndTheDeformingVariant) {
    auto rigid = makeEnv3("", false);
    auto deforming = makeEnv3("", true);
    const std::vector<TriangleMesh> r0 = rigid->frame(0), d0 = deforming->frame(0);
    const std::vector<TriangleMesh> r1 = rigid->frame(37), d1 = deforming->frame(37);
    EXPECT_NE(r0[0].vertices, r1[0].vertices);
    EXPECT_LT(shapeChange(r0[0], r1[0]), 1e-9);
    EXPECT_EQ(r0[1].vertices, r1[1].vertices);
    EXPECT_GT(shapeChange(d0[0], d1[0]), 1e-3);
    EXPECT_EQ(d0[1].vertices, d1[1].vertices);
    EXPECT_NE(rigid->name(), "");
}

TEST(Env3, RealMeshesWhenFetched) {
    const std::string dir = defaultDataDir();
    if (!std::filesystem::exists(std::filesystem::path(dir) / "bunny00.off") ||
        !std::filesystem::exists(std::filesystem::path(dir) / "ChineseDragon-10kv.off")) {
        GTEST_SKIP() << "run scripts/fetch_meshes.sh to test the real meshes";
    }
    bool standIns = true;
    auto env = makeEnv3(dir, true, &standIns);
    EXPECT_FALSE(standIns);
    checkEnv3(*env, 75408, 19994);
}

// ---------------------------------------------------------------------------------------------------------------
// Random scenes

TEST(RandomScene, DeterministicInTheBoxAndMixed) {
    RandomSceneOptions o;
    o.objects = 40;
    const auto a = makeRandomScene(99, o);
    EXPECT_TRUE(sameMeshes(a, makeRandomScene(99, o)));
    EXPECT_FALSE(sameMeshes(a, makeRandomScene(100, o)));
    ASSERT_EQ(a.size(), 40u);
    int degenerate = 0, open = 0;
    for (const TriangleMesh& m : a) {
        EXPECT_GE(m.triangles.size(), static_cast<std::size_t>(o.minTriangles / 2));
        EXPECT_LE(m.triangles.size(), static_cast<std::size_t>(o.maxTriangles * 6 / 5));
        const Aabb b = boundsOf(m);
        EXPECT_TRUE((b.min.array() >= -1e-9).all() && (b.max.array() <= o.boxSize + 1e-9).all());
        for (const auto& t : m.triangles) {
            const Vec3 n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
            if (n.norm() < 1e-12) ++degenerate;
        }
        if (!isClosedOriented(m)) ++open;
    }
    EXPECT_GT(degenerate, 0);
    EXPECT_GT(open, 0);
}

TEST(RandomScene, ClosedShapesOnlyWithoutSoups) {
    RandomSceneOptions o;
    o.objects = 30;
    o.soups = false;
    for (const TriangleMesh& m : makeRandomScene(5, o)) {
        EXPECT_TRUE(isClosedOriented(m));
        EXPECT_GT(signedVolume(m), 0.0);
    }
    o.objects = 0;
    EXPECT_TRUE(makeRandomScene(5, o).empty());
    o.objects = -1;
    EXPECT_THROW(makeRandomScene(5, o), std::invalid_argument);
}

TEST(RandomScene, AFairFractionOfObjectsIntersect) {
    RandomSceneOptions o;
    o.objects = 20;
    int inContact = 0, total = 0;
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
        const auto scene = makeRandomScene(seed, o);
        std::vector<bool> touched(scene.size(), false);
        for (std::size_t i = 0; i < scene.size(); ++i)
            for (std::size_t j = i + 1; j < scene.size(); ++j)
                if (anyIntersection(scene[i], scene[j])) touched[i] = touched[j] = true;
        inContact += static_cast<int>(std::count(touched.begin(), touched.end(), true));
        total += static_cast<int>(scene.size());
    }
    EXPECT_GE(inContact, total / 5);
    EXPECT_LE(inContact, total * 9 / 10);
}

TEST(DataDir, EnvironmentVariableOverridesTheSourceTree) {
    const char* old = std::getenv("CULLIDE_DATA_DIR");
    const std::string saved = old != nullptr ? old : "";
    ::setenv("CULLIDE_DATA_DIR", "/some/where", 1);
    EXPECT_EQ(defaultDataDir(), "/some/where");
    ::unsetenv("CULLIDE_DATA_DIR");
    const std::string fallback = defaultDataDir();
    EXPECT_GE(fallback.size(), std::string("/data/meshes").size());
    EXPECT_EQ(fallback.substr(fallback.size() - 12), "/data/meshes");
    if (old != nullptr) ::setenv("CULLIDE_DATA_DIR", saved.c_str(), 1);
}

}  // namespace
}  // namespace cullide::scenes
