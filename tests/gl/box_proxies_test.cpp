// Meshes against box-only proxies (Bullet's primitives on a landscape): the GPU culler answers them from its box
// trees over surviving triangles; the pairs must be exactly the reference culler's (every triangle's box against
// the proxy box), with few and with many (> 16) partners, touching, near and far boxes, with and without margin.
#include "Compare.h"
#include "GlTestSupport.h"
#include "VisibilityLockstep.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>

namespace cullide::test {
namespace {

/// A bumpy height-field grid in x/z, n × n cells, two triangles each.
TriangleMesh landscape(int n, double size) {
    TriangleMesh m;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            const double x = size * i / n, z = size * j / n;
            m.vertices.emplace_back(x, 0.3 * std::sin(0.7 * x) * std::cos(0.5 * z), z);
        }
    auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return m;
}

TEST(BoxProxies, SameMeshProxyPairsAsTheReference) {
    for (const int proxies : {5, 60}) {  // few partners (per-triangle filter) and many (group filter)
        for (const double margin : {0.0, 0.05}) {
            Settings settings;
            settings.margin = margin;
            CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
            const std::vector<TriangleMesh> meshes = {landscape(48, 20.0)};
            std::vector<Object> objects = asObjects(meshes);
            std::mt19937 rng(static_cast<unsigned>(proxies * 7 + (margin > 0 ? 1 : 0)));
            std::uniform_real_distribution<double> xz(-1.0, 21.0);
            std::uniform_real_distribution<double> y(-0.2, 0.9);   // above, touching or inside the bumps
            std::uniform_real_distribution<double> half(0.05, 0.6);
            for (int i = 0; i < proxies; ++i) {
                Object box;
                const Vec3 c(xz(rng), y(rng), xz(rng));
                const Vec3 h = Vec3::Constant(half(rng));
                box.box.min = c - h;
                box.box.max = c + h;
                objects.push_back(box);
            }
            // A box whose bottom face lies exactly on the highest vertex, plus the margin (closed intervals: it
            // touches), and one just above the margin.
            Vec3 top = meshes[0].vertices[0];
            for (const Vec3& v : meshes[0].vertices)
                if (v.y() > top.y()) top = v;
            Object touching;
            touching.box.min = Vec3(top.x() - 0.05, top.y() + margin, top.z() - 0.05);
            touching.box.max = touching.box.min + Vec3(0.1, 0.5, 0.1);
            objects.push_back(touching);
            Object clear;
            clear.box.min = Vec3(5, 0.3 + margin + 1e-3, 5);
            clear.box.max = Vec3(6, 1.0, 6);
            objects.push_back(clear);

            Result reference;
            Result result;
            createReferenceCuller(settings)->run(objects, reference);
            culler->run(objects, result);
            std::vector<std::pair<std::uint32_t, std::uint32_t>> expected, got;
            for (const ObjectPair& p : reference.pairs) expected.emplace_back(p.a, p.b);
            for (const ObjectPair& p : result.pairs) got.emplace_back(p.a, p.b);
            ASSERT_FALSE(expected.empty());
            const auto touchingId = static_cast<std::uint32_t>(objects.size() - 2);
            if (margin == 0.0) {
                EXPECT_NE(std::find(expected.begin(), expected.end(), std::make_pair(0u, touchingId)), expected.end())
                    << "the touching box must pair with the landscape";
            }
            ASSERT_LT(expected.size(), objects.size() - 1) << "some proxies must be culled for the test to mean much";
            EXPECT_EQ(got, expected) << proxies << " proxies, margin " << margin;
        }
    }
}

// The same kind of scene with every level run (GPU levels forced) and held to the CPU reference iteration by
// iteration: the proxies are items of both levels (boxes), tall ones standing out of the landscape, so that the
// triangle level's first view must hold them as well as the triangles.
TEST(BoxProxies, TheLevelsHoldToTheReferenceInLockstep) {
    const Settings settings = lockstepSettings({Pipeline::Auto, Mode::Reliable, Backend::Compute, 64});
    CULLIDE_GPU_CULLER_OR_SKIP(probe, settings);
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    std::unique_ptr<Culler> reference = createReferenceCuller(settings);
    const std::vector<TriangleMesh> meshes = {landscape(32, 10.0)};
    std::vector<Object> objects = asObjects(meshes);
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> xz(-0.5, 10.5);
    std::uniform_real_distribution<double> height(0.2, 3.0);
    for (int i = 0; i < 12; ++i) {
        Object box;
        const Vec3 c(xz(rng), 0.0, xz(rng));
        box.box.min = c - Vec3(0.3, 0.2, 0.3);
        box.box.max = c + Vec3(0.3, height(rng), 0.3);
        objects.push_back(box);
    }
    Result got;
    const Comparison c = runAndCompare(*culler, *reference, objects, got);
    EXPECT_EQ(got.stats.gpuFallbacks, 0u) << got.stats.gpuError;
    EXPECT_EQ(c.missed, 0u) << c.firstMissed;
    EXPECT_TRUE(c.objectPairsEqual);
    EXPECT_EQ(log->mismatches, 0u) << log->summary();
    EXPECT_GE(log->levelsAhead, 1u) << log->summary();
    EXPECT_FALSE(got.pairs.empty()) << "proxies on the landscape";
}

}  // namespace
}  // namespace cullide::test
