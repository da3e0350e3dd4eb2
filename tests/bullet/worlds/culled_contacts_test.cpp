// The culled path loses no contact: a pair that Bullet's own pipeline gives a point with distance <= 0 gets a point
// through the swap in the same detection, with any culling switch on (alone, or all of them), for shape margins 0 and
// 0.04, with the object levels btDbvtBroadphase, btAxisSweep3 and bt32BitAxisSweep3. Two collision worlds see the same
// poses: Bullet's default pipeline (its broadphase of the same kind) and the swap with the culler the application
// gets by default (on this machine its CPU path; GPU levels where a hardware device is). Poses: touching (a vertex of
// one shape placed on a triangle of the other: float rounding decides whether Bullet sees them a hair apart or a
// hair inside) and interpenetrating (the same, pushed in), and for two GImpact meshes random overlapping poses, among
// which Bullet's clip method makes points from triangles behind each other that are not near (the culling margin
// rule, bullet_adapter/src/broadphase/CullingPolicy.h).
#include "broadphase/CullingPolicy.h"
#include "cullide/Culler.h"
#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletCollisionCommon.h>
#include <gtest/gtest.h>

#include "GlTestSupport.h"

#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace cullide::test {
namespace {

enum class Level { Dbvt, AxisSweep, AxisSweep32 };
const char* name(Level l) { return l == Level::Dbvt ? "dbvt" : l == Level::AxisSweep ? "axis-sweep" : "axis-sweep-32"; }

std::unique_ptr<btBroadphaseInterface> makeLevel(Level l) {
    const btVector3 lo(-100, -100, -100), hi(100, 100, 100);
    if (l == Level::AxisSweep) return std::make_unique<btAxisSweep3>(lo, hi);
    if (l == Level::AxisSweep32) return std::make_unique<bt32BitAxisSweep3>(lo, hi);
    return std::make_unique<btDbvtBroadphase>();
}

/// A triangle mesh with the arrays Bullet's shapes read.
struct Mesh {
    std::vector<btScalar> v;
    std::vector<int> idx;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    void finish() {
        array = std::make_unique<btTriangleIndexVertexArray>(int(idx.size() / 3), idx.data(), int(3 * sizeof(int)),
                                                             int(v.size() / 3), v.data(), int(3 * sizeof(btScalar)));
    }
    btVector3 vertex(int i) const { return btVector3(v[3 * i], v[3 * i + 1], v[3 * i + 2]); }
    int triangles() const { return int(idx.size() / 3); }
    int vertices() const { return int(v.size() / 3); }
};

Mesh torusMesh() {
    Mesh m;
    const int segments = 24, sides = 12;
    const double R = 1.0, r = 0.35;
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const double u = 2 * M_PI * i / segments, w = 2 * M_PI * j / sides;
            m.v.insert(m.v.end(), {btScalar((R + r * std::cos(w)) * std::cos(u)), btScalar(r * std::sin(w)),
                                   btScalar((R + r * std::cos(w)) * std::sin(u))});
        }
    for (int i = 0; i < segments; ++i)
        for (int j = 0; j < sides; ++j) {
            const int a = i * sides + j, b = ((i + 1) % segments) * sides + j;
            const int c = ((i + 1) % segments) * sides + (j + 1) % sides, d = i * sides + (j + 1) % sides;
            m.idx.insert(m.idx.end(), {a, b, c, a, c, d});
        }
    m.finish();
    return m;
}

/// A bumpy 12 x 12 terrain patch, 3 units wide.
Mesh terrainMesh() {
    Mesh m;
    const int n = 12;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j)
            m.v.insert(m.v.end(), {btScalar(-1.5 + 3.0 * i / n), btScalar(0.15 * std::sin(2.1 * i) * std::cos(1.7 * j)),
                                   btScalar(-1.5 + 3.0 * j / n)});
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
            m.idx.insert(m.idx.end(), {a, b, c, b, d, c});
        }
    m.finish();
    return m;
}

/// The shapes of one test, sharing their meshes; margins as given.
struct Shapes {
    Mesh torus = torusMesh();
    Mesh terrain = terrainMesh();
    std::unique_ptr<btGImpactMeshShape> gimpact;
    std::unique_ptr<btBvhTriangleMeshShape> bvh;
    std::unique_ptr<btConvexHullShape> hull;
    std::unique_ptr<btBoxShape> box;
    std::vector<btVector3> hullPoints;
    explicit Shapes(btScalar margin) {
        gimpact = std::make_unique<btGImpactMeshShape>(torus.array.get());
        gimpact->setMargin(margin);
        gimpact->updateBound();
        bvh = std::make_unique<btBvhTriangleMeshShape>(terrain.array.get(), true);
        bvh->setMargin(margin);
        std::mt19937 rng(3);
        std::uniform_real_distribution<float> u(-1, 1);
        hull = std::make_unique<btConvexHullShape>();
        for (int i = 0; i < 24; ++i) {
            btVector3 p(u(rng), u(rng), u(rng));
            p = p.normalized() * btScalar(0.5);
            hullPoints.push_back(p);
            hull->addPoint(p, false);
        }
        hull->recalcLocalAabb();
        hull->setMargin(margin);
        box = std::make_unique<btBoxShape>(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.5)));
        box->setMargin(margin);
    }
};

/// Bullet's default pipeline or the swap, as a collision world of two objects.
struct World {
    btDefaultCollisionConfiguration config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<btCollisionWorld> world;
    btCollisionObject a, b;

    World(Level level, const std::vector<CulledKind>* culled, btCollisionShape* sa, btCollisionShape* sb,
          const Settings& settings = Settings{}) {
        if (culled == nullptr) {
            broadphase = makeLevel(level);
            dispatcher = std::make_unique<btCollisionDispatcher>(&config);
        } else {
            auto bp = std::make_unique<CullideBroadphase>(settings);
            if (level != Level::Dbvt) bp->setObjectLevel(makeLevel(level));
            for (const CulledKind k : {CulledKind::GImpactPair, CulledKind::GImpactMesh, CulledKind::GImpactConvex,
                                       CulledKind::ConvexMesh})
                bp->setCulling(k, Culling::Off);
            for (const CulledKind k : *culled) bp->setCulling(k, Culling::On);
            dispatcher = std::make_unique<CullideCollisionDispatcher>(&config, bp.get());
            broadphase = std::move(bp);
        }
        btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher.get());
        world = std::make_unique<btCollisionWorld>(dispatcher.get(), broadphase.get(), &config);
        a.setCollisionShape(sa);
        b.setCollisionShape(sb);
        world->addCollisionObject(&a);
        world->addCollisionObject(&b);
    }
    ~World() {
        world->removeCollisionObject(&b);
        world->removeCollisionObject(&a);
    }
    /// Detects at B's pose, B added anew (each pose a first encounter: nothing the broadphase keeps per pair, such
    /// as a pair found interpenetrating skipping the culler for a few steps, carries over); the number of points and
    /// the deepest distance.
    std::pair<int, double> detect(const btTransform& tb) {
        world->removeCollisionObject(&b);
        b.setWorldTransform(tb);
        world->addCollisionObject(&b);
        world->performDiscreteCollisionDetection();
        int points = 0;
        double deepest = 1e30;
        for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
            const btPersistentManifold* mf = dispatcher->getManifoldByIndexInternal(m);
            for (int c = 0; c < mf->getNumContacts(); ++c) {
                ++points;
                deepest = std::min(deepest, double(mf->getContactPoint(c).getDistance()));
            }
        }
        return {points, deepest};
    }
};

btQuaternion randomRotation(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1, 1);
    btQuaternion q(u(rng), u(rng), u(rng), u(rng) + 1.5f);
    return q.normalized();
}

/// A point of a triangle of `m` (barycentric, in float as Bullet computes).
btVector3 pointOn(const Mesh& m, std::mt19937& rng) {
    const int t = std::uniform_int_distribution<int>(0, m.triangles() - 1)(rng);
    std::uniform_real_distribution<float> u(0.05f, 0.95f);
    float s = u(rng), w = u(rng);
    if (s + w > 1) {
        s = 1 - s;
        w = 1 - w;
    }
    return m.vertex(m.idx[3 * t]) * (1 - s - w) + m.vertex(m.idx[3 * t + 1]) * s + m.vertex(m.idx[3 * t + 2]) * w;
}

struct Agreement {
    int bulletPairs = 0;  ///< poses where Bullet gives a point with distance <= 0
    int lost = 0;         ///< ... and the swap none
    std::string first;
};

/// B's poses touching A (a point `onB` of B, in its frame, placed on a point of A), then moved by `pushIn` toward A's
/// inside, roughly (negative: away, into the gap their margins bridge).
template <class PointOnB>
void touchingPoses(World& bullet, World& swap, const Mesh& aSurface, PointOnB onB, float pushIn, int poses,
                   std::mt19937& rng, Agreement& out) {
    for (int k = 0; k < poses; ++k) {
        const btVector3 p = pointOn(aSurface, rng);
        const btQuaternion q = randomRotation(rng);
        const btVector3 vb = onB(rng);
        btTransform tb(q, p - quatRotate(q, vb));
        tb.setOrigin(tb.getOrigin() - p.normalized() * pushIn);
        const auto want = bullet.detect(tb);
        const auto got = swap.detect(tb);
        if (want.first == 0 || want.second > 0) continue;
        ++out.bulletPairs;
        if (got.first == 0) {
            if (out.lost++ == 0) out.first = "pose " + std::to_string(k) + ", Bullet's deepest " + std::to_string(want.second);
        }
    }
}

const std::vector<CulledKind> kAll{CulledKind::GImpactPair, CulledKind::GImpactMesh, CulledKind::GImpactConvex,
                                   CulledKind::ConvexMesh};

/// For each kind of pair: each switch alone, and all of them, at both margins and the three object levels, with the
/// culler the application gets by default (`gpuLevels` false: its CPU path here); with `gpuLevels`, the culler's GPU
/// visibility levels (which prune triangles by the culling margin itself, where the CPU path's box tests keep more),
/// every switch on, one object level, fewer poses (llvmpipe).
void checkKind(CulledKind kind, bool gpuLevels = false) {
    Settings culler;
    if (gpuLevels) {
        culler.gpuLevels = GpuLevels::Always;
        culler.resolution = 64;
        culler.exactThreshold = 0;  // the levels prune however few triangles are left
    }
    const std::vector<Level> levels =
        gpuLevels ? std::vector<Level>{Level::Dbvt} : std::vector<Level>{Level::Dbvt, Level::AxisSweep, Level::AxisSweep32};
    const std::vector<bool> alls = gpuLevels ? std::vector<bool>{true} : std::vector<bool>{false, true};
    const int poses = gpuLevels ? 20 : 40;
    for (const btScalar margin : {btScalar(0), btScalar(0.04)})
        for (const Level level : levels)
            for (const bool all : alls) {
                Shapes s(margin);
                const std::vector<CulledKind> alone{kind};
                const std::vector<CulledKind>& on = all ? kAll : alone;
                btCollisionShape* sa = kind == CulledKind::GImpactMesh || kind == CulledKind::ConvexMesh
                                           ? static_cast<btCollisionShape*>(s.bvh.get())
                                           : s.gimpact.get();
                const Mesh& aSurface = sa == s.bvh.get() ? s.terrain : s.torus;
                std::mt19937 rng(17);
                Agreement agreement;
                const auto run = [&](btCollisionShape* sb, auto onB) {
                    World bullet(level, nullptr, sa, sb);
                    World swap(level, &on, sa, sb, culler);
                    // Touching, interpenetrating, and (with margins) apart by most of the two margins: Bullet's points
                    // then lie within the margins, at negative distances, from triangles that do not touch.
                    for (const float push : {0.0f, 0.05f, -1.7f * float(margin)})
                        touchingPoses(bullet, swap, aSurface, onB, push, poses, rng, agreement);
                };
                if (kind == CulledKind::GImpactPair || kind == CulledKind::GImpactMesh) {
                    run(s.gimpact.get(), [&](std::mt19937& r) { return pointOn(s.torus, r); });
                } else {
                    run(s.hull.get(), [&](std::mt19937& r) {
                        return s.hullPoints[std::uniform_int_distribution<std::size_t>(0, s.hullPoints.size() - 1)(r)];
                    });
                    if (kind == CulledKind::GImpactConvex)
                        run(s.box.get(), [&](std::mt19937& r) {
                            const btVector3 h = s.box->getHalfExtentsWithMargin();
                            std::uniform_int_distribution<int> sign(0, 1);
                            return btVector3(sign(r) ? h.x() : -h.x(), sign(r) ? h.y() : -h.y(), sign(r) ? h.z() : -h.z());
                        });
                }
                const std::string what = std::string("margin ") + std::to_string(margin) + ", " + name(level) +
                                         (all ? ", every switch on" : ", this switch alone");
                EXPECT_GT(agreement.bulletPairs, poses / 2) << what;  // the poses do touch
                EXPECT_EQ(agreement.lost, 0) << what << ": " << agreement.first;
            }
}

TEST(CulledContacts, GImpactPairsTouchingOrInterpenetrating) { checkKind(CulledKind::GImpactPair); }
TEST(CulledContacts, GImpactAgainstTriangleMeshes) { checkKind(CulledKind::GImpactMesh); }
TEST(CulledContacts, GImpactAgainstConvexShapes) { checkKind(CulledKind::GImpactConvex); }
TEST(CulledContacts, HullsAgainstTriangleMeshes) { checkKind(CulledKind::ConvexMesh); }

TEST(CulledContacts, EveryKindWithGpuLevels) {
    Settings gpu;
    gpu.gpuLevels = GpuLevels::Always;
    CULLIDE_GPU_CULLER_OR_SKIP(probe, gpu);
    for (const CulledKind kind :
         {CulledKind::GImpactPair, CulledKind::GImpactMesh, CulledKind::GImpactConvex, CulledKind::ConvexMesh})
        checkKind(kind, true);
}

/// Two GImpact meshes at random overlapping poses: among them poses where Bullet's only points come from triangles
/// behind each other that are not near (none within the culling margin); the swap still gives the pair a point,
/// with the culler's CPU path and with its GPU visibility levels (which prune such triangles: each is fully visible
/// from some side).
void checkNotNear(const Settings& culler, const std::vector<btScalar>& margins, int poses) {
    for (const btScalar margin : margins) {
        Shapes s(margin);
        World bullet(Level::Dbvt, nullptr, s.gimpact.get(), s.gimpact.get());
        World swap(Level::Dbvt, &kAll, s.gimpact.get(), s.gimpact.get(), culler);
        cullide::Settings settings;
        settings.margin = bullet::pairReach({bullet::GeometryKind::GImpactMesh, double(margin), 1.0, 2.0},
                                            {bullet::GeometryKind::GImpactMesh, double(margin), 1.0, 2.0},
                                            bullet::BreakingRule{});
        auto reference = createReferenceCuller(settings);
        TriangleMesh local;
        for (int i = 0; i < s.torus.vertices(); ++i) {
            const btVector3 v = s.torus.vertex(i);
            local.vertices.push_back({v.x(), v.y(), v.z()});
        }
        for (int t = 0; t < s.torus.triangles(); ++t)
            local.triangles.push_back({std::uint32_t(s.torus.idx[3 * t]), std::uint32_t(s.torus.idx[3 * t + 1]),
                                       std::uint32_t(s.torus.idx[3 * t + 2])});
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(-1, 1);
        int withPoint = 0, notNear = 0, lost = 0;
        for (int k = 0; k < poses; ++k) {
            const btTransform tb(randomRotation(rng), btVector3(1.2f * u(rng), 0.8f * u(rng), 1.2f * u(rng)));
            const auto want = bullet.detect(tb);
            const auto got = swap.detect(tb);
            if (want.first == 0 || want.second > 0) continue;
            ++withPoint;
            lost += got.first == 0 ? 1 : 0;
            TriangleMesh placed = local;
            for (Vec3& p : placed.vertices) {
                const btVector3 x = tb * btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z()));
                p = Vec3(x.x(), x.y(), x.z());
            }
            std::vector<Object> objects(2);
            objects[0].mesh = &local;
            objects[1].mesh = &placed;
            Result near;
            reference->run(objects, near);
            notNear += near.pairs.empty() || near.pairs[0].triangles.empty() ? 1 : 0;
        }
        EXPECT_GT(withPoint, poses / 2) << "margin " << margin;
        EXPECT_GT(notNear, 3) << "margin " << margin << ": poses whose points come from triangles that are not near";
        EXPECT_EQ(lost, 0) << "margin " << margin << " (" << notNear << " poses with no triangle pair near)";
    }
}

TEST(CulledContacts, GImpactPointsFromTrianglesThatAreNotNear) {
    checkNotNear(Settings{}, {btScalar(0), btScalar(0.02)}, 600);
}

TEST(CulledContacts, GImpactPointsFromTrianglesThatAreNotNearWithGpuLevels) {
    Settings gpu;
    gpu.gpuLevels = GpuLevels::Always;
    gpu.resolution = 64;  // llvmpipe: every pose is a first frame of a new pair
    CULLIDE_GPU_CULLER_OR_SKIP(probe, gpu);
    checkNotNear(gpu, {btScalar(0)}, 250);
}

}  // namespace
}  // namespace cullide::test
