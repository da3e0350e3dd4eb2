// The breakable scene (BreakableScene.h): it fractures on impact, is deterministic, runs the same under every
// Bullet pipeline, moves under the CULLIDE pipeline as under Bullet's default one, and names an unreadable mesh.
#include "GlTestSupport.h"

#include "cullide/demo/BreakableScene.h"

#include <gtest/gtest.h>

#include <exception>
#include <string>
#include <vector>

namespace cullide::demo {
namespace {

TEST(BreakableScene, FracturesOnImpactAndIsDeterministic) {
    CULLIDE_GPU_CULLER_OR_SKIP(probe, Settings{});
    BreakableOptions options;
    options.seed = 5;
    BreakableScene a(options), b(options);
    const std::size_t initial = a.worldMeshes().size();
    std::size_t initialTriangles = 0;
    for (const auto& m : a.worldMeshes()) initialTriangles += m.triangles.size();
    EXPECT_EQ(initial, 2u);
    int frame = 0;
    for (; frame < 60 && a.fractures() == 0; ++frame) {
        a.step();
        b.step();
    }
    ASSERT_GT(a.fractures(), 0) << "the dragon did not break within 60 frames";
    for (int k = 0; k < 5; ++k) a.step(), b.step();
    const auto ma = a.worldMeshes(), mb = b.worldMeshes();
    EXPECT_GT(ma.size(), initial) << "fracture must add bodies";
    EXPECT_EQ(a.bodyNames(), b.bodyNames());
    ASSERT_EQ(ma.size(), mb.size());
    for (std::size_t i = 0; i < ma.size(); ++i) EXPECT_EQ(ma[i].vertices, mb[i].vertices) << a.bodyNames()[i];
    // Triangle counts change: the dragon's triangles are cut into the pieces' (the gap drops some, clipping adds).
    std::size_t before = 0;
    for (const auto& m : std::vector<TriangleMesh>{ma.begin(), ma.end()}) before += m.triangles.size();
    EXPECT_EQ(a.lastFrame().triangles, before);
    EXPECT_NE(a.lastFrame().triangles, initialTriangles);
}

/// The frame at which the scene first fractures (-1: not within 60 frames).
int fractureFrame(CollisionPipeline pipeline) {
    BreakableOptions options;
    options.pipeline = pipeline;
    BreakableScene scene(options);
    EXPECT_EQ(scene.cullideBroadphase() != nullptr, pipeline == CollisionPipeline::Cullide);
    for (int f = 0; f < 60; ++f) {
        scene.step();
        if (scene.fractures() > 0) return f;
    }
    return -1;
}

TEST(BreakableScene, BulletPipelinesRunTheSameScene) {
    // Bullet's own pipelines need no GL. Before the first contact the three pipelines simulate the same free fall,
    // so the impact (and the fracture) comes at the same frame.
    const int bulletDbvt = fractureFrame(CollisionPipeline::BulletDbvt);
    const int axisSweep = fractureFrame(CollisionPipeline::BulletAxisSweep);
    ASSERT_GE(bulletDbvt, 0);
    EXPECT_EQ(axisSweep, bulletDbvt);
    CULLIDE_GPU_CULLER_OR_SKIP(probe, Settings{});
    EXPECT_EQ(fractureFrame(CollisionPipeline::Cullide), bulletDbvt);
}

// The two-line swap must not change the simulation: with its defaults (GImpact pairs get Bullet's contacts) the
// breakable scene moves as under Bullet's default pipeline, bit for bit, through the first contacts and the fracture.
TEST(BreakableScene, CullidePipelineMovesAsBulletsDefaultPipeline) {
    CULLIDE_GPU_CULLER_OR_SKIP(probe, Settings{});
    BreakableOptions options;
    options.pipeline = CollisionPipeline::BulletDbvt;
    options.recordContacts = true;
    BreakableScene bullet(options);
    options.pipeline = CollisionPipeline::Cullide;
    BreakableScene swapped(options);
    std::size_t contacts = 0;
    const auto key = [](const BreakableContact& c) {
        return std::make_tuple(c.body0, c.body1, c.part0, c.index0, c.part1, c.index1, c.distance);
    };
    for (int frame = 0; frame < 45; ++frame) {
        bullet.step();
        swapped.step();
        ASSERT_EQ(swapped.lastFrame().contacts, bullet.lastFrame().contacts) << "frame " << frame;
        // Every point recorded, each the same (bodies, triangle keys, distance) in both pipelines.
        const auto& want = bullet.lastStepContacts();
        const auto& got = swapped.lastStepContacts();
        ASSERT_EQ(want.size(), bullet.lastFrame().contacts) << "frame " << frame;
        ASSERT_EQ(got.size(), want.size()) << "frame " << frame;
        for (std::size_t i = 0; i < want.size(); ++i) ASSERT_EQ(key(got[i]), key(want[i])) << "frame " << frame;
        const auto a = bullet.worldMeshes(), b = swapped.worldMeshes();
        ASSERT_EQ(a.size(), b.size()) << "frame " << frame;
        for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(b[i].vertices, a[i].vertices) << "frame " << frame;
        contacts += bullet.lastFrame().contacts;
    }
    EXPECT_GT(bullet.fractures(), 0);
    EXPECT_GT(contacts, 100u);  // the run reaches the contacts (not a test of free fall)
}

TEST(BreakableScene, UnreadableMeshIsAClearError) {
    BreakableOptions options;
    options.fallingMesh = "/nonexistent/bunny.off";
    try {
        BreakableScene scene(options);
        FAIL() << "expected an exception";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/bunny.off"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace cullide::demo
