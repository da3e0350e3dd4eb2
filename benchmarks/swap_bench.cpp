// cullide-swap-bench: typical Bullet scenes stepped with Bullet's default pipeline (btDbvtBroadphase +
// btCollisionDispatcher), with btAxisSweep3, and with the README's two-line swap (CullideBroadphase +
// CullideCollisionDispatcher), side by side in one process (issue #12, item 7).
//
//   cullide-swap-bench [--steps N] [--env-frames N] [--scene NAME]... [--json FILE] [--culling auto|on|off]
//                      [--gimpact-pair-culling] [--gimpact-mesh-culling] [--gimpact-convex-culling]
//                      [--convex-mesh-culling] [--auto-culling-anywhere]
//                      [--no-penetration-fallback] [--narrow-phase-threads N] [--sap-object-level]
//
// The culling switches are the broadphase's defaults (Culling::Auto) unless set: --culling sets all four, the
// --*-culling flags set one On; --auto-culling-anywhere lets Auto trial without a hardware GL device.
//
// --sap-object-level: the CULLIDE world's object level is a btAxisSweep3 with the SAP world's bounds
// (CullideBroadphase::setObjectLevel, for applications that used btAxisSweep3) instead of the default btDbvtBroadphase.
//
// Scenes: rigid-body dynamics worlds of the kinds Bullet's own benchmarks use, and the paper's environments as
// collision-only btCollisionWorlds (*-world; the first min(--steps, --env-frames) frames, default 40), and the
// breakable demo's scene and a soft-body scene where the demo's library is built (each world its own run; see
// runBreakable, runSoftBodies).
//
// The worlds run in lockstep: every step each world is stepped once (timed, the order rotating), then the default
// world's body states are copied into the others, so all three detect collisions on identical states every step.
// Their timings are comparable step by step, and "lost pairs" are exact: object pairs with contact points after the
// default world's step but not after the CULLIDE world's (on the same state). Prints one table row per scene;
// --json writes the figures (docs/swap.md, scripts/bench.sh).
#include "BenchScene.h"
#include "BulletMesh.h"
#include "SeededRandom.h"
#include "cullide/Timer.h"
#include "cullide/TriangleTest.h"
#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"
#ifdef CULLIDE_SWAP_BENCH_DEMO_SCENES
#include "cullide/demo/BreakableScene.h"
#include "cullide/demo/SoftToriScene.h"

#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#endif

#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace {

using cullide::Timer;

enum class Pipeline { Dbvt, Sap, Cullide };
constexpr Pipeline kPipelines[] = {Pipeline::Dbvt, Pipeline::Sap, Pipeline::Cullide};

using Random = cullide::bench::SeededRandom;

/// CullideBroadphase::setDeepPenetrationFallback for the CULLIDE world (--no-penetration-fallback clears it).
bool g_penetrationFallback = true;
/// The CULLIDE world's culling switches, by cullide::CulledKind: Auto (the default) unless --culling auto|on|off sets
/// all four, or --gimpact-pair-culling, --gimpact-mesh-culling, --gimpact-convex-culling, --convex-mesh-culling set
/// one On.
std::array<cullide::Culling, 4> g_culling{cullide::Culling::Auto, cullide::Culling::Auto, cullide::Culling::Auto,
                                          cullide::Culling::Auto};
/// CullideBroadphase::setAutoCullingOnAnyDevice (--auto-culling-anywhere): Auto trials without a hardware GL device.
bool g_autoAnyDevice = false;
/// CullideCollisionDispatcher::setNarrowPhaseThreads for the CULLIDE world (--narrow-phase-threads N; 0: default).
unsigned g_narrowPhaseThreads = 0;
/// The CULLIDE world's object level: btAxisSweep3 with the SAP world's bounds (--sap-object-level) or the default.
bool g_sapObjectLevel = false;
#ifdef CULLIDE_SWAP_BENCH_DEMO_SCENES
constexpr bool kDemoScenes = true;  ///< the demo's breakable and soft scenes are built in (their library exists)
#else
constexpr bool kDemoScenes = false;
#endif

/// Shapes and mesh data shared by the three worlds of a scene (one set, as an application would share them).
struct Shapes {
    std::vector<std::unique_ptr<btCollisionShape>> owned;
    std::vector<std::unique_ptr<btTriangleIndexVertexArray>> arrays;
    std::vector<std::vector<btScalar>> vertexData;
    std::vector<std::vector<int>> indexData;
    std::vector<std::vector<float>> heightData;

    template <typename T>
    T* own(T* shape) {
        owned.emplace_back(shape);
        return shape;
    }

    btTriangleIndexVertexArray* mesh(std::vector<btScalar> vertices, std::vector<int> indices) {
        vertexData.push_back(std::move(vertices));
        indexData.push_back(std::move(indices));
        btIndexedMesh part;
        part.m_numTriangles = static_cast<int>(indexData.back().size() / 3);
        part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(indexData.back().data());
        part.m_triangleIndexStride = 3 * static_cast<int>(sizeof(int));
        part.m_numVertices = static_cast<int>(vertexData.back().size() / 3);
        part.m_vertexBase = reinterpret_cast<const unsigned char*>(vertexData.back().data());
        part.m_vertexStride = 3 * static_cast<int>(sizeof(btScalar));
        arrays.push_back(std::make_unique<btTriangleIndexVertexArray>());
        arrays.back()->addIndexedMesh(part, PHY_INTEGER);
        return arrays.back().get();
    }

    /// The rolling terrain of the landscape scenes: height at (x, z), within [-2.1, 2.1].
    static double terrainHeight(double x, double z) {
        return 1.5 * std::sin(0.21 * x) * std::cos(0.17 * z) + 0.6 * std::sin(0.5 * x + 0.3 * z);
    }

    /// A height-field patch of cells x cells quads as a static BVH mesh, origin at its corner.
    btBvhTriangleMeshShape* landscape(int cells, double cell, double x0, double z0) {
        std::vector<btScalar> v;
        std::vector<int> idx;
        for (int z = 0; z <= cells; ++z)
            for (int x = 0; x <= cells; ++x) {
                const double wx = x0 + x * cell, wz = z0 + z * cell;
                v.insert(v.end(), {btScalar(wx), btScalar(terrainHeight(wx, wz)), btScalar(wz)});
            }
        for (int z = 0; z < cells; ++z)
            for (int x = 0; x < cells; ++x) {
                const int a = z * (cells + 1) + x;
                idx.insert(idx.end(), {a, a + cells + 1, a + 1, a + 1, a + cells + 1, a + cells + 2});
            }
        return own(new btBvhTriangleMeshShape(mesh(std::move(v), std::move(idx)), true));
    }

    /// A heightfield of (cells + 1)^2 samples `cell` apart, centred on the origin (Bullet centres it on its box).
    btHeightfieldTerrainShape* heightfield(int cells, double cell) {
        std::vector<float> h;
        for (int z = 0; z <= cells; ++z)
            for (int x = 0; x <= cells; ++x) {
                const double wx = (x - 0.5 * cells) * cell, wz = (z - 0.5 * cells) * cell;
                h.push_back(float(terrainHeight(wx, wz)));
            }
        heightData.push_back(std::move(h));
        auto* shape = own(new btHeightfieldTerrainShape(cells + 1, cells + 1, heightData.back().data(), btScalar(1),
                                                        btScalar(-2.5), btScalar(2.5), 1, PHY_FLOAT, false));
        shape->setLocalScaling(btVector3(btScalar(cell), 1, btScalar(cell)));
        return shape;
    }

    btGImpactMeshShape* torus(double R, double r, int segments, int sides, double margin = 0.02) {
        std::vector<btScalar> v;
        std::vector<int> idx;
        cullide::bench::torusArrays(R, r, segments, sides, v, idx);
        auto* shape = own(new btGImpactMeshShape(mesh(std::move(v), std::move(idx))));
        shape->setMargin(btScalar(margin));
        shape->updateBound();
        return shape;
    }

    /// A bumpy closed ellipsoid (2 * segments * (rings - 1) triangles), a stand-in for GimpactTestDemo's bunny:
    /// radii (1.3 r, r, 0.9 r), each vertex's radius scaled by a seeded factor in [0.85, 1.15].
    btGImpactMeshShape* blob(double r, int segments, int rings, double margin, Random& rng) {
        std::vector<btScalar> v{0, btScalar(r), 0};
        for (int j = 1; j < rings; ++j)
            for (int i = 0; i < segments; ++i) {
                const double th = M_PI * j / rings, ph = 2 * M_PI * i / segments, k = rng.uniform(0.85, 1.15);
                v.insert(v.end(), {btScalar(1.3 * r * k * std::sin(th) * std::cos(ph)), btScalar(r * k * std::cos(th)),
                                   btScalar(0.9 * r * k * std::sin(th) * std::sin(ph))});
            }
        v.insert(v.end(), {0, btScalar(-r), 0});
        std::vector<int> idx;
        const int south = 1 + (rings - 1) * segments;
        for (int i = 0; i < segments; ++i) idx.insert(idx.end(), {0, 1 + (i + 1) % segments, 1 + i});
        for (int j = 0; j < rings - 2; ++j)
            for (int i = 0; i < segments; ++i) {
                const int a = 1 + j * segments + i, b = 1 + j * segments + (i + 1) % segments;
                const int c = a + segments, d = b + segments;
                idx.insert(idx.end(), {a, b, c, b, d, c});
            }
        for (int i = 0; i < segments; ++i)
            idx.insert(idx.end(), {south, 1 + (rings - 2) * segments + i, 1 + (rings - 2) * segments + (i + 1) % segments});
        auto* shape = own(new btGImpactMeshShape(mesh(std::move(v), std::move(idx))));
        shape->setMargin(btScalar(margin));
        shape->updateBound();
        return shape;
    }

    btConvexHullShape* hull(Random& rng, int points, double sx, double sy, double sz) {
        auto* h = own(new btConvexHullShape());
        for (int p = 0; p < points; ++p) {
            // Points on a rough ellipsoid: polyhedral features, no degenerate slivers.
            const double a = rng.uniform(0, 2 * M_PI), c = rng.uniform(-1, 1), s = std::sqrt(1 - c * c);
            h->addPoint(btVector3(btScalar(sx * s * std::cos(a)), btScalar(sy * c), btScalar(sz * s * std::sin(a))),
                        p == points - 1);
        }
        h->optimizeConvexHull();
        return h;
    }
};

/// What a scene puts in a world: bodies (shape, mass, transform) and, optionally, ray tests per step.
struct BodySpec {
    btCollisionShape* shape;
    btScalar mass;
    btTransform transform;
    btVector3 velocity = btVector3(0, 0, 0);  ///< initial linear velocity
    bool kinematic = false;                    ///< CF_KINEMATIC_OBJECT, never deactivated (mass 0)
};
struct SceneSpec {
    std::string name;
    std::string what;
    std::vector<BodySpec> bodies;
    int raysPerStep = 0;
    bool gimpact = false;
    btScalar gravity = -10;  ///< along y
    /// Run on every world before each step (the same on each: kinematic motion, launches), with the step index and
    /// the world's bodies in BodySpec order.
    std::function<void(int step, const std::vector<btRigidBody*>& bodies)> beforeStep{};
};

btTransform at(double x, double y, double z) {
    return btTransform(btQuaternion::getIdentity(), btVector3(btScalar(x), btScalar(y), btScalar(z)));
}

SceneSpec boxesFalling(Shapes& s) {
    SceneSpec sc{"boxes-3000", "3,000 boxes falling on a ground box", {}};
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(40, 1, 40))), 0, at(0, -1, 0)});
    btCollisionShape* box = s.own(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.4), btScalar(0.4))));
    for (int i = 0; i < 3000; ++i)
        sc.bodies.push_back({box, 1, at(-14 + (i % 15) * 2.0, 1 + (i / 225) * 1.2, -14 + ((i / 15) % 15) * 2.0)});
    return sc;
}

SceneSpec pyramidWallsTower(Shapes& s) {
    SceneSpec sc{"pyramid-walls", "~1,000 boxes: a pyramid, two walls and a tower", {}};
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(50, 1, 50))), 0, at(0, -1, 0)});
    btCollisionShape* box = s.own(new btBoxShape(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5))));
    for (int level = 0; level < 20; ++level)  // pyramid: 210 boxes
        for (int i = 0; i < 20 - level; ++i) sc.bodies.push_back({box, 1, at(i - 0.5 * (19 - level), 0.5 + level, -10)});
    for (int wall = 0; wall < 2; ++wall)  // walls: 2 x 300
        for (int row = 0; row < 15; ++row)
            for (int i = 0; i < 20; ++i)
                sc.bodies.push_back({box, 1, at(-10 + i * 1.0 + (row % 2) * 0.5, 0.5 + row, 2 + wall * 6)});
    for (int level = 0; level < 50; ++level)  // tower: 50 x 4
        for (int k = 0; k < 4; ++k) sc.bodies.push_back({box, 1, at(20 + (k % 2) * 1.0, 0.5 + level, (k / 2) * 1.0)});
    return sc;
}

SceneSpec hullStack(Shapes& s) {
    SceneSpec sc{"hulls-1000", "1,000 convex hulls (40 points) stacked in 10 columns", {}};
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(40, 1, 40))), 0, at(0, -1, 0)});
    Random rng(11);
    std::vector<btCollisionShape*> hulls;
    for (int k = 0; k < 8; ++k) hulls.push_back(s.hull(rng, 40, 0.5, 0.4, 0.45));
    for (int i = 0; i < 1000; ++i)
        sc.bodies.push_back({hulls[static_cast<std::size_t>(i) % hulls.size()], 1,
                             at(-9 + (i % 10) * 2.0, 0.5 + (i / 100) * 0.9, -9 + ((i / 10) % 10) * 2.0)});
    return sc;
}

/// ~32K triangles of static BVH landscape in 4 parts, ~1,000 bodies of `kinds` dropped on it.
SceneSpec overLandscape(Shapes& s, std::string name, std::string what, const std::vector<btCollisionShape*>& kinds) {
    SceneSpec sc{std::move(name), std::move(what), {}};
    for (int p = 0; p < 4; ++p)  // 4 parts of 64 x 64 cells (8,192 triangles each)
        sc.bodies.push_back({s.landscape(64, 0.75, -48 + (p % 2) * 48.0, -48 + (p / 2) * 48.0), 0, at(0, 0, 0)});
    Random rng(5);
    for (int i = 0; i < 1000; ++i)
        sc.bodies.push_back({kinds[static_cast<std::size_t>(i) % kinds.size()], 1,
                             at(rng.uniform(-44, 44), rng.uniform(3, 9), rng.uniform(-44, 44))});
    return sc;
}

SceneSpec primitivesOnLandscape(Shapes& s) {
    return overLandscape(s, "landscape-prims", "1,000 boxes/spheres/capsules over 4 BVH parts (32K triangles)",
                         {s.own(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35)))),
                          s.own(new btSphereShape(btScalar(0.4))),
                          s.own(new btCapsuleShape(btScalar(0.25), btScalar(0.6)))});
}

SceneSpec hullsOnLandscape(Shapes& s) {
    Random rng(3);
    std::vector<btCollisionShape*> kinds;
    for (int k = 0; k < 6; ++k) kinds.push_back(s.hull(rng, 40, 0.5, 0.4, 0.45));
    return overLandscape(s, "landscape-hulls", "1,000 hulls (40 points) over 4 BVH parts (32K triangles)", kinds);
}

SceneSpec hullsOnLandscapeRays(Shapes& s) {
    SceneSpec sc = hullsOnLandscape(s);
    sc.name = "landscape-rays";
    sc.what = "landscape-hulls + 500 long ray tests a step";
    sc.raysPerStep = 500;
    return sc;
}

SceneSpec toriPile(Shapes& s) {
    SceneSpec sc{"tori-pile", "120 GImpact tori (1,024 triangles each) piling on a ground box", {}};
    sc.gimpact = true;
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(20, 1, 20))), 0, at(0, -1, 0)});
    btCollisionShape* torus = s.torus(1.0, 0.3, 32, 16);
    Random rng(9);
    for (int i = 0; i < 120; ++i) {
        btTransform t = at(-6 + (i % 5) * 3.0, 1.5 + (i / 25) * 3.0, -6 + ((i / 5) % 5) * 3.0);
        t.setRotation(btQuaternion(btVector3(rng.uniform(-1, 1), 1, rng.uniform(-1, 1)).normalized(),
                                   rng.uniform(0, 3)));
        sc.bodies.push_back({torus, 1, t});
    }
    return sc;
}

/// Bullet's old GimpactTestDemo in spirit, with every mesh at GImpact margin 0: a kinematic torus turning and
/// drifting above a column of dynamic tori (crossed in turn, as the demo stacks them), two tori touching tip to tip on
/// the ground (their outer equators meet at a vertex: float rounding decides whether Bullet sees them apart or a
/// hair inside each other), and bunny stand-ins shot into the column every 30 steps (parked without gravity until
/// then).
SceneSpec gimpactDemo(Shapes& s) {
    SceneSpec sc{"gimpact-demo", "GimpactTestDemo-like: margin-0 GImpact tori and bunnies, a kinematic torus, bunnies shot in", {}};
    sc.gimpact = true;
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(50, 1, 50))), 0, at(0, -10, 0)});
    btGImpactMeshShape* torus = s.torus(2.0, 0.7, 24, 12, 0.0);
    Random rng(11);
    btGImpactMeshShape* bunny = s.blob(1.2, 20, 12, 0.0, rng);
    const btQuaternion flat(btVector3(0, 0, 1), btScalar(M_PI / 2));
    const btQuaternion crossed = flat * btQuaternion(btVector3(0, 1, 0), btScalar(M_PI / 2));
    btTransform kinematic = at(0, 18, -5);
    kinematic.setRotation(crossed);
    sc.bodies.push_back({torus, 0, kinematic, btVector3(0, 0, 0), true});
    double height = 18;
    for (int i = 0; i < 6; ++i) {
        height -= 2.5;
        btTransform t = at(0, height, -5);
        t.setRotation(i % 2 == 0 ? flat : crossed);
        sc.bodies.push_back({torus, 1, t});
    }
    sc.bodies.push_back({torus, 1, at(-16, -8.3, 6)});
    sc.bodies.push_back({torus, 1, at(-16 + 2 * (2.0 + 0.7), -8.3, 6)});
    const std::size_t firstBunny = sc.bodies.size();
    constexpr int kBunnies = 4;
    for (int i = 0; i < kBunnies; ++i) sc.bodies.push_back({bunny, 2, at(-40 - 6 * i, 30, -30)});
    sc.beforeStep = [firstBunny](int step, const std::vector<btRigidBody*>& bodies) {
        if (step == 0)
            for (int i = 0; i < kBunnies; ++i) bodies[firstBunny + std::size_t(i)]->setGravity(btVector3(0, 0, 0));
        btRigidBody& k = *bodies[1];
        btTransform t = k.getWorldTransform();
        t.setOrigin(t.getOrigin() + btVector3(btScalar(-0.02), 0, 0));
        t.setRotation(t.getRotation() * btQuaternion(btVector3(1, 0, 0), btScalar(0.03)));
        k.setWorldTransform(t);
        k.getMotionState()->setWorldTransform(t);
        if (step % 30 == 10 && step / 30 < kBunnies) {
            btRigidBody& b = *bodies[firstBunny + std::size_t(step / 30)];
            btTransform launch = at(-14, 8 + step % 7, -5 + 0.5 * (step % 3));
            launch.setRotation(btQuaternion(btVector3(1, btScalar(0.3), 0).normalized(), btScalar(0.1 * step)));
            b.setWorldTransform(launch);
            b.getMotionState()->setWorldTransform(launch);
            b.setGravity(btVector3(0, -10, 0));
            b.setLinearVelocity(btVector3(20, 2, 0));
            b.setAngularVelocity(btVector3(0, 0, 0));
            b.activate(true);
        }
    };
    return sc;
}

/// GImpact meshes resting side by side on a static plane (Bullet's GImpact-plane algorithm: a vertex loop per mesh).
SceneSpec toriOnPlane(Shapes& s) {
    SceneSpec sc{"tori-plane", "144 GImpact tori (1,024 triangles each) dropped side by side on a static plane", {}};
    sc.gimpact = true;
    sc.bodies.push_back({s.own(new btStaticPlaneShape(btVector3(0, 1, 0), 0)), 0, at(0, 0, 0)});
    btCollisionShape* torus = s.torus(1.0, 0.3, 32, 16);
    Random rng(4);
    for (int i = 0; i < 144; ++i) {
        btTransform t = at(-18.7 + (i % 12) * 3.4, 1.0 + rng.uniform(0, 1), -18.7 + (i / 12) * 3.4);
        t.setRotation(btQuaternion(btVector3(rng.uniform(-0.3, 0.3), 1, rng.uniform(-0.3, 0.3)).normalized(),
                                   rng.uniform(0, 3)));
        sc.bodies.push_back({torus, 1, t});
    }
    return sc;
}

/// A world in units of 1e-3 (millimetres in metres): sizes, margins, positions and gravity scaled, while Bullet's
/// broadphase fattening (0.05) and contact breaking threshold (0.02) stay absolute. Every pair is in the cache and
/// the threshold reaches across whole objects: no GImpact candidate triangle is out of reach.
SceneSpec smallUnits(Shapes& s) {
    constexpr double u = 1e-3;
    SceneSpec sc{"small-units", "4 GImpact tori, 28 boxes, spheres, hulls on a ground box, all at 1e-3 units", {}};
    sc.gimpact = true;
    sc.gravity = btScalar(-10 * u);
    const btScalar margin(btScalar(0.04 * u));
    const auto scaledMargin = [&](btCollisionShape* shape) {
        shape->setMargin(margin);
        return shape;
    };
    sc.bodies.push_back({scaledMargin(s.own(new btBoxShape(btVector3(20, 1, 20) * btScalar(u)))), 0, at(0, -u, 0)});
    btGImpactMeshShape* torus = s.torus(u, 0.35 * u, 16, 10);
    torus->setMargin(margin);
    torus->updateBound();
    Random rng(17);
    btCollisionShape* box = scaledMargin(s.own(new btBoxShape(btVector3(1, 1, 1) * btScalar(0.4 * u))));
    btCollisionShape* ball = s.own(new btSphereShape(btScalar(0.4 * u)));
    btCollisionShape* hull = scaledMargin(s.hull(rng, 24, 0.5 * u, 0.4 * u, 0.45 * u));
    btCollisionShape* const kinds[] = {box, ball, hull, box, ball, hull, box, torus};  // 4 tori, 28 convex shapes
    for (int i = 0; i < 32; ++i) {
        btTransform t = at(rng.uniform(-5, 5) * u, (2.0 + 0.6 * i) * u, rng.uniform(-5, 5) * u);
        t.setRotation(btQuaternion(btVector3(rng.uniform(-1, 1), 1, rng.uniform(-1, 1)).normalized(),
                                   rng.uniform(0, 3)));
        sc.bodies.push_back({kinds[i % 8], 1, t});
    }
    return sc;
}

/// Compound bodies, as applications model furniture and debris: 400 tables (a top and four legs), chairs (a seat, a
/// back, four legs) and L-shaped pieces (two boxes), dropped in a heap on a ground box.
SceneSpec compoundHeap(Shapes& s) {
    SceneSpec sc{"compounds-400", "400 compounds (tables, chairs, L pieces: 2-6 boxes each) heaped on a ground box",
                 {}};
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(30, 1, 30))), 0, at(0, -1, 0)});
    const auto box = [&](double x, double y, double z) {
        return s.own(new btBoxShape(btVector3(btScalar(x), btScalar(y), btScalar(z))));
    };
    const auto part = [](btCompoundShape* c, btCollisionShape* child, double x, double y, double z) {
        c->addChildShape(at(x, y, z), child);
    };
    auto* table = s.own(new btCompoundShape());
    part(table, box(0.6, 0.05, 0.4), 0, 0.45, 0);
    for (int k = 0; k < 4; ++k) part(table, box(0.05, 0.2, 0.05), k % 2 ? 0.5 : -0.5, 0.2, k / 2 ? 0.3 : -0.3);
    auto* chair = s.own(new btCompoundShape());
    part(chair, box(0.25, 0.04, 0.25), 0, 0.3, 0);
    part(chair, box(0.25, 0.3, 0.04), 0, 0.6, -0.22);
    for (int k = 0; k < 4; ++k) part(chair, box(0.03, 0.15, 0.03), k % 2 ? 0.2 : -0.2, 0.15, k / 2 ? 0.2 : -0.2);
    auto* piece = s.own(new btCompoundShape());
    part(piece, box(0.5, 0.1, 0.1), 0, 0, 0);
    part(piece, box(0.1, 0.4, 0.1), -0.4, 0.5, 0);
    btCollisionShape* kinds[] = {table, chair, piece};
    Random rng(29);
    for (int i = 0; i < 400; ++i) {
        btTransform t = at(-9 + (i % 8) * 2.6, 1 + (i / 64) * 1.6, -9 + ((i / 8) % 8) * 2.6);
        t.setRotation(btQuaternion(btVector3(rng.uniform(-0.3, 0.3), 1, rng.uniform(-0.3, 0.3)).normalized(),
                                   rng.uniform(0, 3)));
        sc.bodies.push_back({kinds[i % 3], 1, t});
    }
    return sc;
}

/// Compounds of 2-4 hulls, as a convex decomposition (V-HACD and the like) gives an application its non-convex
/// bodies, dropped on the landscape: compound-mesh pairs whose children meet triangles, and compound-compound pairs.
SceneSpec compoundsOnLandscape(Shapes& s) {
    Random rng(37);
    std::vector<btCollisionShape*> kinds;
    for (int k = 0; k < 4; ++k) {
        auto* c = s.own(new btCompoundShape());
        const int parts = 2 + k % 3;
        for (int p = 0; p < parts; ++p) {
            const double angle = 2 * M_PI * p / parts;
            c->addChildShape(at(0.35 * std::cos(angle), 0.1 * p, 0.35 * std::sin(angle)),
                             s.hull(rng, 24, 0.35, 0.3, 0.3));
        }
        kinds.push_back(c);
    }
    return overLandscape(s, "landscape-compounds",
                         "1,000 compounds of 2-4 hulls (24 points) over 4 BVH parts (32K triangles)", kinds);
}

/// A heightfield terrain (128 x 128 cells, 32K triangles) with 1,000 boxes, spheres, capsules and cylinders dropped
/// on it.
SceneSpec primitivesOnHeightfield(Shapes& s) {
    SceneSpec sc{"heightfield-prims", "1,000 boxes/spheres/capsules/cylinders over a 128 x 128 heightfield", {}};
    sc.bodies.push_back({s.heightfield(128, 0.75), 0, at(0, 0, 0)});
    const btScalar r = btScalar(0.3);
    std::vector<btCollisionShape*> kinds = {s.own(new btBoxShape(btVector3(btScalar(0.4), r, btScalar(0.35)))),
                                            s.own(new btSphereShape(btScalar(0.4))),
                                            s.own(new btCapsuleShape(btScalar(0.25), btScalar(0.6))),
                                            s.own(new btCylinderShape(btVector3(r, r, r)))};
    Random rng(31);
    for (int i = 0; i < 1000; ++i)
        sc.bodies.push_back({kinds[static_cast<std::size_t>(i) % kinds.size()], 1,
                             at(rng.uniform(-44, 44), rng.uniform(3, 9), rng.uniform(-44, 44))});
    return sc;
}

/// bench_run's stepping scene 'stack' (55 boxes in a pyramid on a static box), here in lockstep.
SceneSpec boxPyramid(Shapes& s) {
    SceneSpec sc{"stack", "55 boxes in a pyramid on a static box (bench_run's stepping scene)", {}};
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(20, 1, 20))), 0, at(0, -1, 0)});
    btCollisionShape* box = s.own(new btBoxShape(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5))));
    const int levels = 10;
    for (int level = 0; level < levels; ++level)
        for (int i = 0; i < levels - level; ++i)
            sc.bodies.push_back({box, 1, at((i - 0.5 * (levels - level - 1)) * 1.02, 0.5 + level, 0)});
    return sc;
}

/// A settled scene that mostly sleeps: 5,000 boxes resting side by side in a 100 x 50 grid of 10 x 10 blocks (their
/// neighbours' boxes within the broadphase's fattening), asleep after the first ~2 s, and 6 balls rolled along the
/// lanes between the blocks, waking the boxes they brush.
SceneSpec sleepingBoxes(Shapes& s) {
    SceneSpec sc{"sleeping-5000", "5,000 boxes asleep in blocks on a ground box, 6 balls rolling through", {}};
    sc.bodies.push_back({s.own(new btBoxShape(btVector3(150, 1, 40))), 0, at(0, -1, 0)});
    btCollisionShape* box = s.own(new btBoxShape(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5))));
    for (int i = 0; i < 5000; ++i) {
        const int x = i % 100, z = i / 100;  // blocks of 10 x 10, lanes of 1.5 between them
        sc.bodies.push_back({box, 1, at(-60 + x * 1.02 + (x / 10) * 1.5, 0.5, -30 + z * 1.02 + (z / 10) * 1.5)});
    }
    btCollisionShape* ball = s.own(new btSphereShape(btScalar(0.8)));  // wider than a lane: it brushes the blocks
    for (int k = 0; k < 6; ++k) {  // along x in the lanes between block rows, reaching them after the boxes sleep
        const int row = k % 4 + 1;  // the lane before this block row
        BodySpec b{ball, 2, at(-90 - 12.0 * k, 0.8, -30 + (10 * row - 0.5) * 1.02 + (row - 0.5) * 1.5)};
        b.velocity = btVector3(6, 0, 0);
        sc.bodies.push_back(b);
    }
    return sc;
}

/// Like bench_run's stepping scene 'landscape': 150 primitives and hulls dropped on one 8,192-triangle BVH part.
SceneSpec landscapeSmall(Shapes& s) {
    SceneSpec sc{"landscape-150", "150 boxes/spheres/capsules/hulls (24 points) over one BVH part (8K triangles)", {}};
    sc.bodies.push_back({s.landscape(64, 0.75, -24, -24), 0, at(0, 0, 0)});
    Random rng(7);
    std::vector<btCollisionShape*> kinds = {s.own(new btSphereShape(btScalar(0.4))),
                                            s.own(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35)))),
                                            s.own(new btCapsuleShape(btScalar(0.25), btScalar(0.6)))};
    for (int k = 0; k < 3; ++k) kinds.push_back(s.hull(rng, 24, 0.5, 0.4, 0.45));
    for (int i = 0; i < 150; ++i)
        sc.bodies.push_back({kinds[static_cast<std::size_t>(i) % kinds.size()], 1,
                             at(rng.uniform(-22, 22), rng.uniform(4, 10), rng.uniform(-22, 22))});
    return sc;
}

/// GImpact bodies among others over a static landscape: 60 tori (one shape), 100 hulls and 100 boxes dropped on two
/// BVH parts (16K triangles) - GImpact against BVH, against convex shapes and against GImpact, in one scene.
SceneSpec gimpactLandscape(Shapes& s) {
    SceneSpec sc{"gimpact-landscape", "60 GImpact tori (1,024 triangles), 100 hulls, 100 boxes over 2 BVH parts (16K)",
                 {}};
    sc.gimpact = true;
    for (int p = 0; p < 2; ++p) sc.bodies.push_back({s.landscape(64, 0.5, -32 + p * 32.0, -16), 0, at(0, 0, 0)});
    btCollisionShape* torus = s.torus(1.0, 0.3, 32, 16);
    Random rng(17);
    btCollisionShape* box = s.own(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35))));
    std::vector<btCollisionShape*> hulls;
    for (int k = 0; k < 4; ++k) hulls.push_back(s.hull(rng, 40, 0.5, 0.4, 0.45));
    for (int i = 0; i < 260; ++i) {
        btTransform t = at(rng.uniform(-28, 28), rng.uniform(3, 12), rng.uniform(-12, 12));
        t.setRotation(btQuaternion(btVector3(rng.uniform(-1, 1), 1, rng.uniform(-1, 1)).normalized(),
                                   rng.uniform(0, 3)));
        btCollisionShape* shape = i % 13 < 3 ? torus : i % 2 == 0 ? box : hulls[static_cast<std::size_t>(i) % 4];
        sc.bodies.push_back({shape, 1, t});
    }
    return sc;
}

struct SceneFactory {
    const char* name;
    SceneSpec (*make)(Shapes&);
};
const SceneFactory kScenes[] = {{"boxes-3000", boxesFalling},      {"pyramid-walls", pyramidWallsTower},
                                {"hulls-1000", hullStack},         {"landscape-prims", primitivesOnLandscape},
                                {"landscape-hulls", hullsOnLandscape}, {"landscape-rays", hullsOnLandscapeRays},
                                {"tori-pile", toriPile},           {"stack", boxPyramid},
                                {"landscape-150", landscapeSmall}, {"gimpact-landscape", gimpactLandscape},
                                {"compounds-400", compoundHeap},   {"heightfield-prims", primitivesOnHeightfield},
                                {"landscape-compounds", compoundsOnLandscape}, {"small-units", smallUnits},
                                {"sleeping-5000", sleepingBoxes},  {"tori-plane", toriOnPlane},
                                {"gimpact-demo", gimpactDemo}};

/// A dynamics world that times the parts of its step.
class TimedWorld final : public btDiscreteDynamicsWorld {
public:
    using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;
    void performDiscreteCollisionDetection() override {
        Timer t;
        updateAabbs();
        computeOverlappingPairs();
        broadphaseMs += t.ms();
        t = Timer();
        if (btDispatcher* d = getDispatcher())
            d->dispatchAllCollisionPairs(getBroadphase()->getOverlappingPairCache(), getDispatchInfo(), d);
        narrowMs += t.ms();
    }
    double broadphaseMs = 0, narrowMs = 0;
};

/// The broadphase and dispatcher of a pipeline: Bullet's dbvt or SAP (world box [sapMin, sapMax]), or the two-line
/// swap with the command line's settings.
void makePipeline(Pipeline p, btCollisionConfiguration& config, const btVector3& sapMin, const btVector3& sapMax,
                  std::unique_ptr<btBroadphaseInterface>& broadphase, std::unique_ptr<btCollisionDispatcher>& dispatcher) {
    if (p == Pipeline::Cullide) {
        auto bp = std::make_unique<cullide::CullideBroadphase>();
        bp->setDeepPenetrationFallback(g_penetrationFallback);
        for (std::size_t k = 0; k < g_culling.size(); ++k) bp->setCulling(cullide::CulledKind(k), g_culling[k]);
        bp->setAutoCullingOnAnyDevice(g_autoAnyDevice);
        if (g_sapObjectLevel) bp->setObjectLevel(std::make_unique<btAxisSweep3>(sapMin, sapMax));
        auto d = std::make_unique<cullide::CullideCollisionDispatcher>(&config, bp.get());
        d->setNarrowPhaseThreads(g_narrowPhaseThreads);
        dispatcher = std::move(d);
        broadphase = std::move(bp);
        return;
    }
    dispatcher = std::make_unique<btCollisionDispatcher>(&config);
    if (p == Pipeline::Dbvt)
        broadphase = std::make_unique<btDbvtBroadphase>();
    else
        broadphase = std::make_unique<btAxisSweep3>(sapMin, sapMax);
}

/// Object pairs (lower user index first) with contact points in the dispatcher's manifolds.
std::set<std::pair<int, int>> contactPairsOf(btDispatcher& dispatcher) {
    std::set<std::pair<int, int>> out;
    for (int k = 0; k < dispatcher.getNumManifolds(); ++k) {
        const btPersistentManifold* m = dispatcher.getManifoldByIndexInternal(k);
        if (m->getNumContacts() == 0) continue;
        const int a = m->getBody0()->getUserIndex(), b = m->getBody1()->getUserIndex();
        out.emplace(std::min(a, b), std::max(a, b));
    }
    return out;
}

/// Contact points by object pair (lower user index first): (triangle key, distance) per point, the key being both
/// sides' (part, index) as the narrow phase set them, in the pair's order.
using PointKey = std::array<int, 4>;
using ContactPoints = std::map<std::pair<int, int>, std::vector<std::pair<PointKey, double>>>;
ContactPoints contactPointsOf(btDispatcher& dispatcher) {
    ContactPoints out;
    for (int k = 0; k < dispatcher.getNumManifolds(); ++k) {
        const btPersistentManifold* m = dispatcher.getManifoldByIndexInternal(k);
        const int a = m->getBody0()->getUserIndex(), b = m->getBody1()->getUserIndex();
        for (int c = 0; c < m->getNumContacts(); ++c) {
            const btManifoldPoint& pt = m->getContactPoint(c);
            const PointKey key = a < b ? PointKey{pt.m_partId0, pt.m_index0, pt.m_partId1, pt.m_index1}
                                       : PointKey{pt.m_partId1, pt.m_index1, pt.m_partId0, pt.m_index0};
            out[{std::min(a, b), std::max(a, b)}].emplace_back(key, double(pt.getDistance()));
        }
    }
    return out;
}

/// One pipeline's world of a scene.
struct World {
    Pipeline pipeline;
    btDefaultCollisionConfiguration config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    btSequentialImpulseConstraintSolver solver;
    std::unique_ptr<TimedWorld> world;
    std::vector<std::unique_ptr<btRigidBody>> bodies;
    std::vector<std::unique_ptr<btDefaultMotionState>> motion;
    double stepMs = 0, rayMs = 0;
    std::size_t narrowPairs = 0;  ///< pairs in the pair cache after each step, summed
    std::size_t rayHits = 0;

    World(Pipeline p, const SceneSpec& scene) : pipeline(p) {
        makePipeline(p, config, btVector3(-120, -60, -120), btVector3(120, 200, 120), broadphase, dispatcher);
        if (scene.gimpact) btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher.get());
        world = std::make_unique<TimedWorld>(dispatcher.get(), broadphase.get(), &solver, &config);
        world->setGravity(btVector3(0, scene.gravity, 0));
        for (const BodySpec& b : scene.bodies) {
            btVector3 inertia(0, 0, 0);
            if (b.mass > 0) b.shape->calculateLocalInertia(b.mass, inertia);
            motion.push_back(std::make_unique<btDefaultMotionState>(b.transform));
            btRigidBody::btRigidBodyConstructionInfo info(b.mass, motion.back().get(), b.shape, inertia);
            bodies.push_back(std::make_unique<btRigidBody>(info));
            bodies.back()->setUserIndex(static_cast<int>(bodies.size() - 1));
            bodies.back()->setLinearVelocity(b.velocity);
            if (b.kinematic) {
                bodies.back()->setCollisionFlags(bodies.back()->getCollisionFlags() |
                                                 btCollisionObject::CF_KINEMATIC_OBJECT);
                bodies.back()->setActivationState(DISABLE_DEACTIVATION);
            }
            world->addRigidBody(bodies.back().get());
        }
    }
    ~World() {
        for (auto& b : bodies) world->removeRigidBody(b.get());
    }

    void step(int raysPerStep, int stepIndex) {
        Timer t;
        world->stepSimulation(btScalar(1.0 / 60.0), 0);
        Timer r;
        for (int i = 0; i < raysPerStep; ++i) {  // long rays across the landscape, a new fan every step
            const double a = 2 * M_PI * (i + 0.37 * stepIndex) / raysPerStep;
            const btVector3 from(btScalar(60 * std::cos(a)), 12, btScalar(60 * std::sin(a)));
            const btVector3 to(btScalar(-60 * std::cos(a + 0.5)), -4, btScalar(-60 * std::sin(a + 0.5)));
            btCollisionWorld::ClosestRayResultCallback hit(from, to);
            world->rayTest(from, to, hit);
            rayHits += hit.hasHit() ? 1 : 0;
        }
        rayMs += r.ms();
        stepMs += t.ms();
        narrowPairs += static_cast<std::size_t>(broadphase->getOverlappingPairCache()->getNumOverlappingPairs());
    }

    std::set<std::pair<int, int>> contactPairs() const { return contactPairsOf(*dispatcher); }
    ContactPoints contactPoints() const { return contactPointsOf(*dispatcher); }

    /// Takes over another world's body states (lockstep).
    void copyStatesFrom(const World& from) {
        for (std::size_t i = 0; i < bodies.size(); ++i) {
            const btRigidBody& src = *from.bodies[i];
            btRigidBody& dst = *bodies[i];
            if (dst.isStaticObject()) continue;
            dst.setWorldTransform(src.getWorldTransform());
            dst.setInterpolationWorldTransform(src.getInterpolationWorldTransform());
            dst.setLinearVelocity(src.getLinearVelocity());
            dst.setAngularVelocity(src.getAngularVelocity());
            dst.setInterpolationLinearVelocity(src.getInterpolationLinearVelocity());
            dst.setInterpolationAngularVelocity(src.getInterpolationAngularVelocity());
            dst.forceActivationState(src.getActivationState());
            dst.setDeactivationTime(src.getDeactivationTime());
            motion[i]->setWorldTransform(src.getWorldTransform());
        }
    }
};

struct Row {
    std::string scene, what;
    std::size_t bodies = 0;
    int steps = 0;
    double ms[3] = {0, 0, 0}, broadphaseMs[3] = {0, 0, 0}, narrowMs[3] = {0, 0, 0};
    double pairs[3] = {0, 0, 0};
    std::size_t contactPairSteps = 0, lost = 0, extra = 0;
    /// Steps whose contacts were compared (every step, but for the breakable scene, whose worlds are compared until
    /// they depart: its own run per world, no state copied).
    int comparedSteps = 0;
    /// Culling::Auto's state per kind at the end (CulledKind order; "culled"/"not culled" for On/Off).
    std::array<std::string, 4> autoState;
    cullide::CullideFrameStats last;
    cullide::CullideMemoryStats memory;  ///< what the CULLIDE broadphase keeps after the last step
    double cullidePairs = 0, fallbackPairs = 0, penetrationPairs = 0, apartPairs = 0;  ///< dispatcher, per step
    double threadedPairs = 0;  ///< dispatcher, per step: pairs run by Bullet's algorithms on the narrow-phase threads
    double buildMs = 0, cullMs = 0, recordMs = 0;  ///< CullideBroadphase's stages, per step
    /// Lost pairs explained (explainLost, the first kLostChecks), and of those the meshes without a triangle pair
    /// within the culling margin at the detected state.
    std::size_t lostChecked = 0, lostApart = 0;
    /// Contact error on pairs with contacts in both worlds: points of the default world whose triangle key the
    /// CULLIDE world's manifold lacks, and the difference of the deepest points.
    std::size_t points = 0, pointsMissing = 0, pointsExtra = 0, comparedPairSteps = 0;
    double deepestDiffMax = 0, deepestDiffSum = 0;
    /// GImpact-convex triangles per step: Bullet's query, run, run without the per-triangle reach test
    double convexCandidates = 0, convexTriangles = 0, convexUnchecked = 0;
    /// GImpact-plane vertices per step: those Bullet's loop visits, those tested
    double planeVertices = 0, planeVerticesTested = 0;
};

/// Adds the CULLIDE world's last step (dispatcher and broadphase stages) to the row's per-step means.
void addCullideStep(const cullide::CullideCollisionDispatcher& dispatcher, const cullide::CullideBroadphase& broadphase,
                    int steps, Row& row) {
    const auto& d = dispatcher.getLastStepStats();
    row.cullidePairs += double(d.cullidePairs) / steps;
    row.fallbackPairs += double(d.fallbackPairs) / steps;
    row.penetrationPairs += double(d.penetrationPairs) / steps;
    row.apartPairs += double(d.apartPairs) / steps;
    row.threadedPairs += double(d.threadedPairs) / steps;
    row.convexCandidates += double(d.convexCandidates) / steps;
    row.convexTriangles += double(d.convexTriangles) / steps;
    row.convexUnchecked += double(d.convexUnchecked) / steps;
    row.planeVertices += double(d.planeVertices) / steps;
    row.planeVerticesTested += double(d.planeVerticesTested) / steps;
    const auto& b = broadphase.getLastFrameStats();
    row.buildMs += b.buildMs / steps;
    row.cullMs += b.cullMs / steps;
    row.recordMs += b.recordMs / steps;
}

const cullide::CullideCollisionDispatcher& cullideOf(const btCollisionDispatcher& d) {
    return static_cast<const cullide::CullideCollisionDispatcher&>(d);
}
const cullide::CullideBroadphase& cullideOf(const btBroadphaseInterface& b) {
    return static_cast<const cullide::CullideBroadphase&>(b);
}

/// The CULLIDE world's figures at the end of a run: its last step, what it keeps, the culling switches' states.
void finishRow(const cullide::CullideBroadphase& broadphase, Row& row) {
    row.last = broadphase.getLastFrameStats();
    row.memory = broadphase.getMemoryStats();
    row.comparedSteps = row.steps;
    for (std::size_t k = 0; k < row.autoState.size(); ++k)
        row.autoState[k] = broadphase.getCullingDecision(cullide::CulledKind(k)).state;
}

/// Adds one step's contact error (see Row).
void compareContacts(const ContactPoints& want, const ContactPoints& got, Row& row) {
    for (const auto& [pair, points] : want) {
        const auto it = got.find(pair);
        if (it == got.end()) continue;  // a lost pair: counted as such
        double deepestWant = 1e30, deepestGot = 1e30;
        for (const auto& [key, distance] : points) {
            deepestWant = std::min(deepestWant, distance);
            ++row.points;
            const bool found = std::any_of(it->second.begin(), it->second.end(),
                                           [&](const auto& p) { return p.first == key; });
            row.pointsMissing += found ? 0 : 1;
        }
        for (const auto& p : it->second) {
            deepestGot = std::min(deepestGot, p.second);
            const bool known = std::any_of(points.begin(), points.end(), [&](const auto& w) { return w.first == p.first; });
            row.pointsExtra += known ? 0 : 1;
        }
        ++row.comparedPairSteps;
        row.deepestDiffMax = std::max(row.deepestDiffMax, std::fabs(deepestWant - deepestGot));
        row.deepestDiffSum += std::fabs(deepestWant - deepestGot);
    }
}

constexpr std::size_t kLostChecks = 8;

/// World-space triangles of a concave shape (GImpact or BVH mesh) as Bullet's processAllTriangles yields them.
struct TriangleCollector : btTriangleCallback {
    const btTransform* placement = nullptr;
    std::vector<std::array<cullide::Vec3, 3>> triangles;
    void processTriangle(btVector3* t, int, int) override {
        std::array<cullide::Vec3, 3> w;
        for (int k = 0; k < 3; ++k) {
            const btVector3 v = *placement * t[k];
            w[std::size_t(k)] = cullide::Vec3(double(v.x()), double(v.y()), double(v.z()));
        }
        triangles.push_back(w);
    }
};

std::vector<std::array<cullide::Vec3, 3>> worldTriangles(const btCollisionObject& o, const btTransform& placement) {
    TriangleCollector c;
    c.placement = &placement;
    const btVector3 big(btScalar(1e9), btScalar(1e9), btScalar(1e9));
    static_cast<const btConcaveShape*>(o.getCollisionShape())->processAllTriangles(&c, -big, big);
    return c.triangles;
}

std::string number(double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", x);
    return buf;
}

/// A lost pair, explained on stderr: whether the CULLIDE world still had the object pair, Bullet's deepest point,
/// and for two concave shapes the exact distance of their triangles (brute force): farther apart than the culling
/// margin means Bullet's contacts there are not between touching triangles (GImpact's clip method makes penetration
/// points from triangle pairs whose boxes overlap).
void explainLost(const World& reference, World& cullideWorld, const std::pair<int, int>& p, int step,
                 const std::vector<btTransform>& detectedAt, Row& row) {
    ++row.lostChecked;
    btCollisionObject* a = cullideWorld.bodies[std::size_t(p.first)].get();
    btCollisionObject* b = cullideWorld.bodies[std::size_t(p.second)].get();
    const bool inCache = cullideWorld.broadphase->getOverlappingPairCache()->findPair(a->getBroadphaseHandle(),
                                                                                        b->getBroadphaseHandle());
    double deepest = 1e30;
    for (int k = 0; k < reference.dispatcher->getNumManifolds(); ++k) {
        const btPersistentManifold* m = reference.dispatcher->getManifoldByIndexInternal(k);
        const int x = m->getBody0()->getUserIndex(), y = m->getBody1()->getUserIndex();
        if (std::min(x, y) != p.first || std::max(x, y) != p.second) continue;
        for (int c = 0; c < m->getNumContacts(); ++c)
            deepest = std::min(deepest, double(m->getContactPoint(c).getDistance()));
    }
    long within = -1;  // triangle pairs within the margin (two meshes only)
    const double margin = static_cast<cullide::CullideBroadphase*>(cullideWorld.broadphase.get())->getCullingMargin();
    if (a->getCollisionShape()->isConcave() && b->getCollisionShape()->isConcave()) {
        // At the state both worlds detected collisions on (before the step's integration).
        const auto ta = worldTriangles(*a, detectedAt[std::size_t(p.first)]);
        const auto tb = worldTriangles(*b, detectedAt[std::size_t(p.second)]);
        within = 0;  // brute force with the culler's exact predicate
        for (const auto& x : ta)
            for (const auto& y : tb) within += cullide::trianglesWithin(x[0], x[1], x[2], y[0], y[1], y[2], margin);
        if (within == 0) ++row.lostApart;
    }
    std::fprintf(stderr,
                 "%s: step %d lost pair %d-%d (%s): Bullet's deepest point %.4g; %s\n", row.scene.c_str(), step,
                 p.first, p.second, inCache ? "in the pair cache" : "pruned by the culler", deepest,
                 within < 0 ? "not two meshes"
                         : (std::to_string(within) + " triangle pairs within the margin " + number(margin) +
                            (within == 0 ? " (none: the meshes are farther apart)" : " (a MISSED contact)"))
                               .c_str());
}

Row runScene(const SceneFactory& factory, int steps) {
    Shapes shapes;
    const SceneSpec scene = factory.make(shapes);
    std::vector<std::unique_ptr<World>> worlds;
    for (Pipeline p : kPipelines) worlds.push_back(std::make_unique<World>(p, scene));
    Row row;
    row.scene = scene.name;
    row.what = scene.what;
    row.bodies = scene.bodies.size();
    row.steps = steps;
    std::vector<btTransform> detectedAt(scene.bodies.size());
    for (int s = 0; s < steps; ++s) {
        if (scene.beforeStep)
            for (auto& w : worlds) {
                std::vector<btRigidBody*> bodies;
                for (auto& b : w->bodies) bodies.push_back(b.get());
                scene.beforeStep(s, bodies);
            }
        for (std::size_t i = 0; i < detectedAt.size(); ++i) detectedAt[i] = worlds[0]->bodies[i]->getWorldTransform();
        for (std::size_t k = 0; k < worlds.size(); ++k) worlds[(k + static_cast<std::size_t>(s)) % worlds.size()]
                                                               ->step(scene.raysPerStep, s);
        const auto want = worlds[0]->contactPairs();
        const auto got = worlds[2]->contactPairs();
        row.contactPairSteps += want.size();
        for (const auto& p : want) {
            if (got.count(p)) continue;
            ++row.lost;
            if (row.lostChecked < kLostChecks) explainLost(*worlds[0], *worlds[2], p, s, detectedAt, row);
        }
        for (const auto& p : got) row.extra += want.count(p) ? 0 : 1;
        compareContacts(worlds[0]->contactPoints(), worlds[2]->contactPoints(), row);
        addCullideStep(cullideOf(*worlds[2]->dispatcher), cullideOf(*worlds[2]->broadphase), steps, row);
        for (std::size_t k = 1; k < worlds.size(); ++k) worlds[k]->copyStatesFrom(*worlds[0]);
    }
    for (std::size_t k = 0; k < worlds.size(); ++k) {
        row.ms[k] = worlds[k]->stepMs / steps;
        row.broadphaseMs[k] = worlds[k]->world->broadphaseMs / steps;
        row.narrowMs[k] = worlds[k]->world->narrowMs / steps;
        row.pairs[k] = double(worlds[k]->narrowPairs) / steps;
    }
    finishRow(*static_cast<cullide::CullideBroadphase*>(worlds[2]->broadphase.get()), row);
    return row;
}

/// The paper's environments as an application that uses Bullet as a collision library would model them: a
/// btCollisionWorld of plain btCollisionObjects (default flags) with GImpact mesh shapes (margin 0: the task is the
/// intersecting triangles, as in the side-by-side runs), moved every frame — rigid objects by their transform,
/// deforming ones by new vertices (postUpdate + updateBound). Each world owns its shapes, so each pays its own
/// updates; a frame's time is the update plus performDiscreteCollisionDetection.
struct CollisionSceneSpec {
    const char* name;
    const char* environment;  ///< BenchScene name
    const char* what;
};
const CollisionSceneSpec kCollisionScenes[] = {
    {"env1-world", "env1", "env1 (100 deforming objects, 200 triangles each) in a btCollisionWorld"},
    {"env2-world", "env2", "env2 (6 deforming tori, 20K triangles each) in a btCollisionWorld"},
    {"env3-world", "env3", "env3 (rigid bunny 75K through a static dragon 20K) in a btCollisionWorld"},
    {"env3-deform-world", "env3-deform", "env3 with the bunny deforming, in a btCollisionWorld"}};


using cullide::bench::GImpactBody;

/// One pipeline's collision world of an environment.
struct CollisionWorld {
    Pipeline pipeline;
    btDefaultCollisionConfiguration config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<btCollisionWorld> world;
    std::vector<GImpactBody> bodies;
    double stepMs = 0, updateMs = 0, broadphaseMs = 0, narrowMs = 0;
    std::size_t narrowPairs = 0;

    CollisionWorld(Pipeline p, const cullide::bench::BenchFrame& first) : pipeline(p) {
        // SAP's world box: the first frame's bounds, three times their size (the environments stay inside a box).
        cullide::Aabb box;
        for (const auto& mesh : *first.world)
            for (const cullide::Vec3& v : mesh.vertices) box.grow(v);
        const cullide::Vec3 c = 0.5 * (box.min + box.max);
        const double half = 1.5 * box.extent().maxCoeff() + 1.0;
        const auto bt = [](const cullide::Vec3& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); };
        makePipeline(p, config, bt(c - cullide::Vec3::Constant(half)), bt(c + cullide::Vec3::Constant(half)), broadphase,
                     dispatcher);
        btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher.get());
        world = std::make_unique<btCollisionWorld>(dispatcher.get(), broadphase.get(), &config);
        bodies.resize(first.local->size());
        for (std::size_t i = 0; i < bodies.size(); ++i) {
            bodies[i].build(first, i);  // plain objects: default flags, as a collision-library user leaves them
            world->addCollisionObject(bodies[i].object.get());
        }
    }
    ~CollisionWorld() {
        for (GImpactBody& b : bodies) world->removeCollisionObject(b.object.get());
    }

    /// The frame's motion, then collision detection (timed together, and in parts).
    void step(const cullide::bench::BenchFrame& frame) {
        Timer total;
        for (std::size_t i = 0; i < bodies.size(); ++i) bodies[i].move(frame, i);
        updateMs += total.ms();
        Timer t;
        world->updateAabbs();
        world->computeOverlappingPairs();
        broadphaseMs += t.ms();
        t = Timer();
        dispatcher->dispatchAllCollisionPairs(broadphase->getOverlappingPairCache(), world->getDispatchInfo(),
                                              dispatcher.get());
        narrowMs += t.ms();
        stepMs += total.ms();
        narrowPairs += std::size_t(broadphase->getOverlappingPairCache()->getNumOverlappingPairs());
    }
};

Row runCollisionScene(const CollisionSceneSpec& spec, int frames) {
    cullide::bench::SceneParams params;
    params.name = spec.environment;
    cullide::bench::BenchScene scene(params);
    const cullide::bench::BenchFrame first = scene.frame(0);
    std::vector<std::unique_ptr<CollisionWorld>> worlds;
    for (Pipeline p : kPipelines) worlds.push_back(std::make_unique<CollisionWorld>(p, first));
    Row row;
    row.scene = spec.name;
    row.what = spec.what;
    row.bodies = first.local->size();
    row.steps = frames;
    for (int f = 0; f < frames; ++f) {
        const cullide::bench::BenchFrame frame = scene.frame(f);
        for (std::size_t k = 0; k < worlds.size(); ++k) worlds[(k + std::size_t(f)) % worlds.size()]->step(frame);
        const auto want = contactPairsOf(*worlds[0]->dispatcher);
        const auto got = contactPairsOf(*worlds[2]->dispatcher);
        row.contactPairSteps += want.size();
        for (const auto& p : want) row.lost += got.count(p) ? 0 : 1;
        for (const auto& p : got) row.extra += want.count(p) ? 0 : 1;
        compareContacts(contactPointsOf(*worlds[0]->dispatcher), contactPointsOf(*worlds[2]->dispatcher), row);
        addCullideStep(cullideOf(*worlds[2]->dispatcher), cullideOf(*worlds[2]->broadphase), frames, row);
    }
    for (std::size_t k = 0; k < worlds.size(); ++k) {
        row.ms[k] = worlds[k]->stepMs / frames;
        row.broadphaseMs[k] = worlds[k]->broadphaseMs / frames;
        row.narrowMs[k] = worlds[k]->narrowMs / frames;
        row.pairs[k] = double(worlds[k]->narrowPairs) / frames;
    }
    finishRow(*static_cast<cullide::CullideBroadphase*>(worlds[2]->broadphase.get()), row);
    return row;
}

#ifdef CULLIDE_SWAP_BENCH_DEMO_SCENES
/// A breakable-scene world's contact points by body pair, the bodies numbered by name in `ids` (shared by the worlds).
ContactPoints contactPointsOf(const cullide::demo::BreakableScene& scene, std::map<std::string, int>& ids) {
    const auto id = [&](const std::string& name) { return ids.emplace(name, int(ids.size())).first->second; };
    ContactPoints out;
    for (const cullide::demo::BreakableContact& c : scene.lastStepContacts())
        out[{id(c.body0), id(c.body1)}].emplace_back(PointKey{c.part0, c.index0, c.part1, c.index1}, c.distance);
    return out;
}

/// The breakable demo's scene (the bunny falls through the dragon, which breaks into pieces) with each pipeline,
/// stepped in lockstep from the same start, the order rotating. Bodies appear as the dragon breaks, so states are not
/// copied between worlds: each world runs its own simulation. The swap's world moves as the default's, bit for bit
/// (checked every step: the body meshes, and the contacts as in the other scenes); btAxisSweep3's pair order changes
/// its solve, so its run departs from the others' after the first contacts (same scene, same work). A step's time
/// includes the scene's fracture work, which is the application's own.
Row runBreakable(int steps) {
    using cullide::demo::CollisionPipeline;
    std::vector<std::unique_ptr<cullide::demo::BreakableScene>> worlds;
    for (Pipeline p : kPipelines) {
        cullide::demo::BreakableOptions o;
        o.pipeline = p == Pipeline::Dbvt  ? CollisionPipeline::BulletDbvt
                     : p == Pipeline::Sap ? CollisionPipeline::BulletAxisSweep
                                          : CollisionPipeline::Cullide;
        o.deepPenetrationFallback = g_penetrationFallback;
        o.culling = g_culling[std::size_t(cullide::CulledKind::GImpactPair)];  // the pieces' pairs
        o.narrowPhaseThreads = g_narrowPhaseThreads;
        o.recordContacts = p != Pipeline::Sap;
        worlds.push_back(std::make_unique<cullide::demo::BreakableScene>(o));
    }
    Row row;
    row.scene = "breakable";
    row.what = "the breakable demo: the bunny falls through the dragon, which breaks into pieces";
    row.steps = steps;
    std::map<std::string, int> ids;
    int departed = -1;  // the first step after which the swap's world differs from the default's
    for (int s = 0; s < steps; ++s) {
        for (std::size_t k = 0; k < worlds.size(); ++k)
            worlds[(k + static_cast<std::size_t>(s)) % worlds.size()]->step();
        for (std::size_t k = 0; k < worlds.size(); ++k) {
            const cullide::demo::BreakableFrame& f = worlds[k]->lastFrame();
            row.ms[k] += f.totalMs / steps;
            row.broadphaseMs[k] += f.broadphaseMs / steps;
            row.narrowMs[k] += f.narrowphaseMs / steps;
            row.pairs[k] += double(f.broadphasePairs) / steps;
            row.bodies = std::max(row.bodies, f.bodies);
        }
        // Contacts are compared while the two worlds are identical: from the first step that differs (a contact
        // point the culled path places otherwise moves the pieces otherwise), they are two simulations.
        if (departed < 0) {
            const ContactPoints want = contactPointsOf(*worlds[0], ids), got = contactPointsOf(*worlds[2], ids);
            row.contactPairSteps += want.size();
            for (const auto& p : want) row.lost += got.count(p.first) ? 0 : 1;
            for (const auto& p : got) row.extra += want.count(p.first) ? 0 : 1;
            compareContacts(want, got, row);
            row.comparedSteps = s + 1;
        }
        addCullideStep(*worlds[2]->cullideDispatcher(), *worlds[2]->cullideBroadphase(), steps, row);
        if (departed < 0) {
            const auto a = worlds[0]->worldMeshes(), b = worlds[2]->worldMeshes();
            bool same = a.size() == b.size();
            for (std::size_t i = 0; same && i < a.size(); ++i) same = a[i].vertices == b[i].vertices;
            if (!same) departed = s;
        }
    }
    if (departed >= 0)
        std::fprintf(stderr, "breakable: the swap's world departed from the default pipeline's at step %d\n", departed);
    const int compared = row.comparedSteps;
    finishRow(*worlds[2]->cullideBroadphase(), row);
    row.comparedSteps = compared;
    return row;
}

/// One pipeline's soft-body world: Bullet's soft-rigid world with a cloth patch falling on a static sphere beside a
/// resting box, and the demo's two soft tori (VF_SS faces, SDF_RS) falling on each other onto a floor.
struct SoftWorld {
    btSoftBodyRigidBodyCollisionConfiguration config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    btSequentialImpulseConstraintSolver solver;
    std::unique_ptr<btSoftRigidDynamicsWorld> world;
    btSphereShape sphereShape{btScalar(0.8)};
    btBoxShape boxShape{btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5))};
    std::unique_ptr<btRigidBody> sphere, box;
    std::unique_ptr<btSoftBody> cloth;
    std::unique_ptr<cullide::demo::SoftToriScene> tori;
    double stepMs = 0;
    std::size_t pairs = 0;

    explicit SoftWorld(Pipeline p) {
        makePipeline(p, config, btVector3(-50, -50, -50), btVector3(50, 50, 50), broadphase, dispatcher);
        world = std::make_unique<btSoftRigidDynamicsWorld>(dispatcher.get(), broadphase.get(), &solver, &config);
        cullide::demo::prepareSoftWorld(*world);
        btSoftBodyWorldInfo& info = world->getWorldInfo();
        tori = std::make_unique<cullide::demo::SoftToriScene>(*world);  // its floor's top at y = 0, around x = 0
        sphere = std::make_unique<btRigidBody>(0, nullptr, &sphereShape);
        sphere->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(8, btScalar(0.8), 0)));
        world->addRigidBody(sphere.get());
        btVector3 inertia;
        boxShape.calculateLocalInertia(1, inertia);
        box = std::make_unique<btRigidBody>(1, nullptr, &boxShape, inertia);
        box->setWorldTransform(btTransform(btQuaternion::getIdentity(), btVector3(btScalar(9.3), btScalar(0.5), 0)));
        world->addRigidBody(box.get());
        cloth.reset(btSoftBodyHelpers::CreatePatch(info, btVector3(6, 3, -2), btVector3(10, 3, -2), btVector3(6, 3, 2),
                                                   btVector3(10, 3, 2), 32, 32, 0, true));
        cloth->getCollisionShape()->setMargin(btScalar(0.05));
        cloth->setTotalMass(1);
        world->addSoftBody(cloth.get());
    }
    ~SoftWorld() {
        world->removeSoftBody(cloth.get());
        world->removeRigidBody(box.get());
        world->removeRigidBody(sphere.get());
        tori.reset();
    }

    void step() {
        Timer t;
        world->stepSimulation(btScalar(1.0 / 60.0), 0);
        stepMs += t.ms();
        pairs += static_cast<std::size_t>(broadphase->getOverlappingPairCache()->getNumOverlappingPairs());
    }

    /// Every soft node's position and the box's transform, as bits.
    std::vector<btScalar> state() const {
        std::vector<btScalar> out;
        for (const btSoftBody* b : {cloth.get(), &tori->torus(0), &tori->torus(1)})
            for (int i = 0; i < b->m_nodes.size(); ++i)
                for (int k = 0; k < 3; ++k) out.push_back(b->m_nodes[i].m_x[k]);
        const btTransform& t = box->getWorldTransform();
        for (int k = 0; k < 3; ++k) out.push_back(t.getOrigin()[k]);
        return out;
    }
    /// Soft contacts of the last step: rigid contacts of every soft body, then soft-soft contacts.
    std::size_t softContacts() const {
        std::size_t n = 0;
        for (const btSoftBody* b : {cloth.get(), &tori->torus(0), &tori->torus(1)})
            n += std::size_t(b->m_rcontacts.size()) + std::size_t(b->m_scontacts.size());
        return n;
    }
};

/// Soft bodies through the swap (issue #12: they stay Bullet's, with no per-step overhead above Bullet's own): the
/// three pipelines' soft worlds from the same start, stepped in lockstep, the order rotating. Soft bodies carry their
/// own state (nodes), so each world runs its own simulation; the swap's world is checked every step against the
/// default's (every node and the box as bits: a departure is reported on stderr, with the first step). "Lost" and
/// "extra" count soft contacts (rigid and soft-soft) the swap's world has fewer or more of than the default's.
Row runSoftBodies(int steps) {
    std::vector<std::unique_ptr<SoftWorld>> worlds;
    for (Pipeline p : kPipelines) worlds.push_back(std::make_unique<SoftWorld>(p));
    Row row;
    row.scene = "soft-bodies";
    row.what = "a cloth (32 x 32) on a sphere and a box, two soft tori (VF_SS) falling on each other";
    row.steps = steps;
    row.bodies = 6;
    int departed = -1;
    for (int s = 0; s < steps; ++s) {
        for (std::size_t k = 0; k < worlds.size(); ++k)
            worlds[(k + static_cast<std::size_t>(s)) % worlds.size()]->step();
        const std::size_t want = worlds[0]->softContacts(), got = worlds[2]->softContacts();
        row.contactPairSteps += want;
        row.lost += want > got ? want - got : 0;
        row.extra += got > want ? got - want : 0;
        if (departed < 0) {
            const std::vector<btScalar> a = worlds[0]->state(), b = worlds[2]->state();
            if (a.size() != b.size() || std::memcmp(a.data(), b.data(), a.size() * sizeof(btScalar)) != 0) departed = s;
        }
        addCullideStep(cullideOf(*worlds[2]->dispatcher), cullideOf(*worlds[2]->broadphase), steps, row);
    }
    if (departed >= 0)
        std::fprintf(stderr, "soft-bodies: the swap's world departed from the default pipeline's at step %d\n",
                     departed);
    for (std::size_t k = 0; k < worlds.size(); ++k) {
        row.ms[k] = worlds[k]->stepMs / steps;
        row.pairs[k] = double(worlds[k]->pairs) / steps;
    }
    finishRow(cullideOf(*worlds[2]->broadphase), row);
    return row;
}
#endif

void printRow(const Row& r) {
    const double best = std::min(r.ms[0], r.ms[1]);
    std::printf("%-16s %6zu %5d | %8.2f %8.2f %8.2f | %5.2fx | bp %6.2f/%6.2f/%6.2f nar %7.2f/%7.2f/%7.2f | pairs %8.0f/%8.0f/%8.0f | "
                "lost %zu of %zu (checked %zu: %zu apart) extra %zu | dispatcher: culled %.1f, full %.1f "
                "(penetrating %.1f), apart %.1f, threaded %.1f | culling frame %.2f ms, culler %.2f, records %.2f; last step: %zu object pairs, "
                "%zu pruned | contact keys missing %zu of %zu, extra %zu, deepest point diff max %.3g mean %.3g (%zu pair-steps) | "
                "GImpact-convex triangles %.0f of %.0f (%.0f unchecked) | GImpact-plane vertices %.0f of %.0f | kept: %zu shapes %zu B shared, %zu objects %zu B "
                "(%zu world copies), %.0f B per object | culling: pair %s, mesh %s, convex %s, convex-mesh %s\n",
                r.scene.c_str(), r.bodies, r.steps, r.ms[0], r.ms[1], r.ms[2], r.ms[2] / best, r.broadphaseMs[0],
                r.broadphaseMs[1], r.broadphaseMs[2], r.narrowMs[0], r.narrowMs[1], r.narrowMs[2], r.pairs[0],
                r.pairs[1], r.pairs[2], r.lost, r.contactPairSteps,
                r.lostChecked, r.lostApart, r.extra, r.cullidePairs, r.fallbackPairs, r.penetrationPairs, r.apartPairs, r.threadedPairs, r.buildMs, r.cullMs, r.recordMs, r.last.objectPairs,
                r.last.prunedPairs, r.pointsMissing, r.points, r.pointsExtra, r.deepestDiffMax,
                r.comparedPairSteps ? r.deepestDiffSum / double(r.comparedPairSteps) : 0.0, r.comparedPairSteps,
                r.convexTriangles, r.convexCandidates, r.convexUnchecked, r.planeVerticesTested, r.planeVertices, r.memory.shapes, r.memory.sharedGeometryBytes,
                r.memory.objects, r.memory.objectBytes, r.memory.worldCopies,
                r.memory.objects ? double(r.memory.objectBytes) / double(r.memory.objects) : 0.0,
                r.autoState[0].c_str(), r.autoState[1].c_str(), r.autoState[2].c_str(), r.autoState[3].c_str());
    std::fflush(stdout);
}

void writeJson(const std::string& path, const std::vector<Row>& rows) {
    std::ofstream out(path);
    out << "[\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        char buf[4096];
        std::snprintf(buf, sizeof buf,
                      "  {\"scene\": \"%s\", \"what\": \"%s\", \"bodies\": %zu, \"steps\": %d, \"dbvt_ms\": %.4f, "
                      "\"sap_ms\": %.4f, \"cullide_ms\": %.4f, \"ratio\": %.4f, \"dbvt_broadphase_ms\": %.4f, "
                      "\"sap_broadphase_ms\": %.4f, \"cullide_broadphase_ms\": %.4f, \"dbvt_narrow_ms\": %.4f, "
                      "\"sap_narrow_ms\": %.4f, \"cullide_narrow_ms\": %.4f, \"dbvt_pairs\": %.1f, \"sap_pairs\": %.1f, "
                      "\"cullide_pairs\": %.1f, \"apart_pairs\": %.1f, \"threaded_pairs\": %.1f, \"contact_pair_steps\": %zu, \"lost\": %zu, "
                      "\"lost_checked\": %zu, \"lost_apart\": %zu, \"extra\": %zu, \"culled_pairs\": %zu, "
                      "\"pruned_pairs\": %zu, \"points\": %zu, \"points_missing\": %zu, \"points_extra\": %zu, \"deepest_diff_max\": %.6g, "
                      "\"deepest_diff_mean\": %.6g, \"penetration_fallback\": %s, \"compared_steps\": %d, "
                      "\"culling\": {\"gimpact_pair\": \"%s\", \"gimpact_mesh\": \"%s\", \"gimpact_convex\": \"%s\", "
                      "\"convex_mesh\": \"%s\"}}%s\n",
                      r.scene.c_str(), r.what.c_str(), r.bodies, r.steps, r.ms[0], r.ms[1], r.ms[2],
                      r.ms[2] / std::min(r.ms[0], r.ms[1]), r.broadphaseMs[0], r.broadphaseMs[1], r.broadphaseMs[2],
                      r.narrowMs[0], r.narrowMs[1], r.narrowMs[2], r.pairs[0], r.pairs[1], r.pairs[2], r.apartPairs, r.threadedPairs, r.contactPairSteps, r.lost, r.lostChecked, r.lostApart,
                      r.extra, r.last.culledPairs, r.last.prunedPairs, r.points, r.pointsMissing, r.pointsExtra,
                      r.deepestDiffMax,
                      r.comparedPairSteps ? r.deepestDiffSum / double(r.comparedPairSteps) : 0.0,
                      g_penetrationFallback ? "true" : "false", r.comparedSteps, r.autoState[0].c_str(),
                      r.autoState[1].c_str(), r.autoState[2].c_str(), r.autoState[3].c_str(),
                      i + 1 < rows.size() ? "," : "");
        out << buf;
    }
    out << "]\n";
}

}  // namespace

int main(int argc, char** argv) {
    int steps = 120;
    int envFrames = 40;  // the environments' frames are heavier than a rigid step (env3: ~100K triangles moving)
    std::vector<std::string> only;
    std::string json;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--steps" && i + 1 < argc) {
            steps = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--scene" && i + 1 < argc) {
            only.emplace_back(argv[++i]);
        } else if (a == "--env-frames" && i + 1 < argc) {
            envFrames = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--no-penetration-fallback") {
            g_penetrationFallback = false;
        } else if (a == "--gimpact-pair-culling") {
            g_culling[std::size_t(cullide::CulledKind::GImpactPair)] = cullide::Culling::On;
        } else if (a == "--gimpact-mesh-culling") {
            g_culling[std::size_t(cullide::CulledKind::GImpactMesh)] = cullide::Culling::On;
        } else if (a == "--gimpact-convex-culling") {
            g_culling[std::size_t(cullide::CulledKind::GImpactConvex)] = cullide::Culling::On;
        } else if (a == "--convex-mesh-culling") {
            g_culling[std::size_t(cullide::CulledKind::ConvexMesh)] = cullide::Culling::On;
        } else if (a == "--culling" && i + 1 < argc) {
            const std::string mode = argv[++i];
            if (mode != "auto" && mode != "on" && mode != "off") {
                std::fprintf(stderr, "cullide-swap-bench: --culling expects auto, on or off, got '%s'\n", mode.c_str());
                return 2;
            }
            g_culling.fill(mode == "auto" ? cullide::Culling::Auto
                           : mode == "on" ? cullide::Culling::On
                                          : cullide::Culling::Off);
        } else if (a == "--auto-culling-anywhere") {
            g_autoAnyDevice = true;
        } else if (a == "--narrow-phase-threads" && i + 1 < argc) {
            g_narrowPhaseThreads = static_cast<unsigned>(std::max(0, std::atoi(argv[++i])));
        } else if (a == "--sap-object-level") {
            g_sapObjectLevel = true;
        } else if (a == "--json" && i + 1 < argc) {
            json = argv[++i];
        } else {
            std::fprintf(stderr, "usage: cullide-swap-bench [--steps N] [--env-frames N] [--scene NAME]... [--json FILE] "
                                 "[--culling auto|on|off] [--gimpact-pair-culling] [--gimpact-mesh-culling] "
                                 "[--gimpact-convex-culling] [--convex-mesh-culling] [--auto-culling-anywhere] "
                                 "[--no-penetration-fallback] [--narrow-phase-threads N] "
                                 "[--sap-object-level]\nscenes:");
            for (const SceneFactory& f : kScenes) std::fprintf(stderr, " %s", f.name);
            for (const CollisionSceneSpec& c : kCollisionScenes) std::fprintf(stderr, " %s", c.name);
            if (kDemoScenes) std::fprintf(stderr, " breakable soft-bodies");
            std::fprintf(stderr, "\n");
            return 2;
        }
    }
    for (const std::string& name : only) {
        if ((name == "breakable" || name == "soft-bodies") && kDemoScenes) continue;
        if (std::none_of(std::begin(kScenes), std::end(kScenes), [&](const SceneFactory& f) { return name == f.name; }) &&
            std::none_of(std::begin(kCollisionScenes), std::end(kCollisionScenes),
                         [&](const CollisionSceneSpec& c) { return name == c.name; })) {
            std::fprintf(stderr, "cullide-swap-bench: unknown scene '%s'\n", name.c_str());
            return 2;
        }
    }
    std::printf("%-16s %6s %5s | %8s %8s %8s | %6s | step ms per world (lockstep, same states, order rotating); bp, nar, pairs: dbvt/sap/cullide\n",
                "scene", "bodies", "steps", "dbvt", "sap", "cullide", "ratio");
    std::vector<Row> rows;
    for (const SceneFactory& f : kScenes) {
        if (!only.empty() && std::find(only.begin(), only.end(), f.name) == only.end()) continue;
        rows.push_back(runScene(f, steps));
        printRow(rows.back());
    }
    for (const CollisionSceneSpec& c : kCollisionScenes) {
        if (!only.empty() && std::find(only.begin(), only.end(), c.name) == only.end()) continue;
        rows.push_back(runCollisionScene(c, std::min(steps, envFrames)));
        printRow(rows.back());
    }
#ifdef CULLIDE_SWAP_BENCH_DEMO_SCENES
    // --steps steps (the default 120 covers the fall, the impact and the pieces).
    if (only.empty() || std::find(only.begin(), only.end(), "breakable") != only.end()) {
        rows.push_back(runBreakable(steps));
        printRow(rows.back());
    }
    if (only.empty() || std::find(only.begin(), only.end(), "soft-bodies") != only.end()) {
        rows.push_back(runSoftBodies(steps));
        printRow(rows.back());
    }
#endif
    if (!json.empty()) writeJson(json, rows);
    return 0;
}
