// GImpact meshes against static planes: the dispatcher rules out most vertices of Bullet's plane loop with a cheaper
// bound first (narrowphase/GImpactPlaneContacts.h) and must keep Bullet's manifolds bit for bit — float and
// double vertices, parts, scaling, vertices no triangle uses, tilted and moved planes on either side of the pair,
// meshes deformed with and without a refit — and the bound must never rule out a vertex Bullet's float arithmetic
// puts below the plane.
#include "narrowphase/GImpactPlaneContacts.h"
#include "SceneSupport.h"

#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <vector>

namespace cullide::test {
namespace {

btTransform at(double x, double y, double z, const btQuaternion& q = btQuaternion::getIdentity()) {
    return btTransform(q, btVector3(btScalar(x), btScalar(y), btScalar(z)));
}

/// A GImpact mesh over the test's own arrays: one part per added surface, float or double vertices, and vertices
/// that no triangle uses where asked.
class OwnMesh {
public:
    /// An ellipsoid of rings x segments quads (split in triangles) with the given radii around `centre`, and then
    /// `strays` unused vertices below its bottom (0.06 apart, the first 0.05 below it).
    void addEllipsoid(const btVector3& radii, const btVector3& centre, int rings, int segments, bool doubles,
                      int strays = 0) {
        Part& p = newPart(doubles);
        const double pi = 3.141592653589793;
        for (int r = 0; r <= rings; ++r)
            for (int s = 0; s < segments; ++s) {
                const double theta = pi * r / rings, phi = 2 * pi * s / segments;
                p.add(centre.x() + radii.x() * std::sin(theta) * std::cos(phi), centre.y() + radii.y() * std::cos(theta),
                      centre.z() + radii.z() * std::sin(theta) * std::sin(phi));
            }
        for (int r = 0; r < rings; ++r)
            for (int s = 0; s < segments; ++s) {
                const int a = r * segments + s, b = r * segments + (s + 1) % segments;
                const int c = a + segments, d = b + segments;
                p.indices.insert(p.indices.end(), {a, c, b, b, c, d});
            }
        for (int k = 0; k < strays; ++k) p.add(centre.x(), centre.y() - radii.y() - 0.05 - 0.06 * k, centre.z());
    }
    /// A flat square tile of n x n quads, side `side`, in the part's y = 0 plane.
    void addTile(double side, int n) {
        Part& p = newPart(false);
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n; ++j) p.add(side * (double(i) / n - 0.5), 0.0, side * (double(j) / n - 0.5));
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
                p.indices.insert(p.indices.end(), {a, b, c, b, d, c});
            }
    }
    btGImpactMeshShape* finish(btScalar margin, const btVector3& scaling = btVector3(1, 1, 1)) {
        m_array = std::make_unique<btTriangleIndexVertexArray>();
        for (Part& p : m_parts) {
            btIndexedMesh m;
            m.m_numTriangles = static_cast<int>(p.indices.size() / 3);
            m.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(p.indices.data());
            m.m_triangleIndexStride = 3 * sizeof(int);
            m.m_numVertices = static_cast<int>(p.count());
            m.m_vertexBase = p.doubles ? reinterpret_cast<const unsigned char*>(p.d.data())
                                       : reinterpret_cast<const unsigned char*>(p.f.data());
            m.m_vertexStride = p.doubles ? 3 * sizeof(double) : 3 * sizeof(float);
            m.m_vertexType = p.doubles ? PHY_DOUBLE : PHY_FLOAT;
            m_array->addIndexedMesh(m, PHY_INTEGER);
        }
        m_shape = std::make_unique<btGImpactMeshShape>(m_array.get());
        m_shape->setMargin(margin);
        m_shape->setLocalScaling(scaling);
        m_shape->updateBound();
        return m_shape.get();
    }
    /// Moves every vertex of the float parts to its position as made times `factor`, then (`refit`) refits the
    /// mesh as Bullet asks of deforming GImpact meshes.
    void scaleFromRest(double factor, bool refit) {
        for (Part& p : m_parts) {
            if (p.rest.empty()) p.rest = p.f;
            for (std::size_t i = 0; i < p.f.size(); ++i) p.f[i] = float(p.rest[i] * factor);
        }
        if (!refit) return;
        m_shape->postUpdate();
        m_shape->updateBound();
    }

private:
    struct Part {
        bool doubles = false;
        std::vector<float> f, rest;
        std::vector<double> d;
        std::vector<int> indices;
        void add(double x, double y, double z) {
            if (doubles)
                d.insert(d.end(), {x, y, z});
            else
                f.insert(f.end(), {float(x), float(y), float(z)});
        }
        std::size_t count() const { return (doubles ? d.size() : f.size()) / 3; }
    };
    Part& newPart(bool doubles) {
        m_parts.emplace_back();
        m_parts.back().doubles = doubles;
        return m_parts.back();
    }
    std::vector<Part> m_parts;  // complete before finish(): the array points into the parts' vectors
    std::unique_ptr<btTriangleIndexVertexArray> m_array;
    std::unique_ptr<btGImpactMeshShape> m_shape;
};

/// GImpact bodies dropped on a ground plane (added first) and a tilted, moved plane (added last, so the pairs come
/// in both orders): two-part rocks (float and double vertices, two unused vertices below each, scaled), tori, flat
/// tiles and pebbles.
struct PlaneScene {
    ShapeStore shapes;
    std::vector<std::unique_ptr<OwnMesh>> meshes;
    btCollisionShape* ground = shapes.plane(btVector3(0, 1, 0), btScalar(0));
    btCollisionShape* tilted = shapes.plane(btVector3(0.35f, 1, 0.1f).normalized(), btScalar(0.2));
    std::vector<btCollisionShape*> kinds;

    PlaneScene() {
        OwnMesh& rock = own();
        rock.addEllipsoid(btVector3(0.45f, 0.3f, 0.35f), btVector3(0, 0, 0), 10, 16, false, 2);
        rock.addEllipsoid(btVector3(0.25f, 0.25f, 0.3f), btVector3(0.4f, 0.1f, 0), 8, 12, true, 2);
        kinds.push_back(rock.finish(btScalar(0.02), btVector3(1.2f, 0.9f, 1.1f)));
        OwnMesh& tile = own();
        tile.addTile(0.9, 6);
        kinds.push_back(tile.finish(btScalar(0.03)));
        kinds.push_back(shapes.gimpactTorus(btScalar(0.45), btScalar(0.15), 16, 8, btScalar(0.01)));
        OwnMesh& pebble = own();
        pebble.addEllipsoid(btVector3(0.3f, 0.2f, 0.3f), btVector3(0, 0, 0), 8, 12, false);
        kinds.push_back(pebble.finish(btScalar(0.01)));
    }
    OwnMesh& own() {
        meshes.push_back(std::make_unique<OwnMesh>());
        return *meshes.back();
    }
    void populate(TestWorld& w) const {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w.dispatcher());
        w.addBody(ground, 0, at(0, 0, 0));
        int k = 0;
        for (int layer = 0; layer < 2; ++layer)
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j, ++k) {
                    const btQuaternion turn(btVector3(0.4f, 1, 0.3f).normalized(), btScalar(0.61 * k));
                    w.addBody(kinds[std::size_t(k) % kinds.size()], 1,
                              at(1.4 * (i - 1) + 0.3 * layer, 1.0 + 0.9 * layer, 1.4 * (j - 1), turn));
                }
        w.addBody(tilted, 0, at(2.8, -0.6, 0, btQuaternion(btVector3(0, 1, 0), btScalar(0.4))));
    }
};

TEST(GImpactPlane, ContactsAreBulletsBitForBit) {
    const PlaneScene scene;
    TestWorld reference(PipelineKind::Default);
    TestWorld swap(PipelineKind::Cullide, referenceFactory());
    swap.cullideDispatcher()->setNarrowPhaseThreads(2);  // the mesh-mesh pairs' contacts computed ahead meanwhile
    scene.populate(reference);
    scene.populate(swap);
    EXPECT_EQ(firstDifferingStep(reference, swap, 180, 120), -1);
    const CullideDispatchStats& stats = swap.cullideDispatcher()->getTotalStats();
    std::printf("[ measure  ] %zu GImpact-plane pair-steps, %zu of %zu vertices tested\n", stats.planePairs,
                stats.planeVerticesTested, stats.planeVertices);
    EXPECT_GT(stats.planePairs, 1000u);
    EXPECT_GT(stats.planeVertices, 50000u) << "the bodies lie on the planes";
    EXPECT_LT(stats.planeVerticesTested, stats.planeVertices / 3) << "most vertices are out of reach";
    // Both pair orders made points: the ground (added first) is body 0 of its pairs, the tilted plane body 1.
    std::size_t planeFirst = 0, planeSecond = 0;
    for (int i = 0; i < swap.dispatcher().getNumManifolds(); ++i) {
        const btPersistentManifold* m = swap.dispatcher().getManifoldByIndexInternal(i);
        if (m->getNumContacts() == 0) continue;
        const auto isPlane = [](const btCollisionObject* o) {
            return o->getCollisionShape()->getShapeType() == STATIC_PLANE_PROXYTYPE;
        };
        planeFirst += isPlane(m->getBody0()) ? 1 : 0;
        planeSecond += isPlane(m->getBody1()) ? 1 : 0;
    }
    EXPECT_GT(planeFirst, 0u);
    EXPECT_GT(planeSecond, 0u);
}

/// The SSE2 path (packed float vertices) and the one-by-one path (any other stride) must let the same vertices
/// through: the same points, bit for bit, over many poses of one mesh stored both ways.
TEST(GImpactPlane, PackedAndStridedVerticesGiveTheSamePoints) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(-1, 1);
    const int rings = 20, segments = 30;
    std::vector<float> packed, padded;
    std::vector<int> indices;
    for (int r = 0; r <= rings; ++r)
        for (int k = 0; k < segments; ++k) {
            const double theta = 3.141592653589793 * r / rings, phi = 6.283185307179586 * k / segments;
            const float v[3] = {float(0.6 * std::sin(theta) * std::cos(phi) + 0.01 * unit(rng)),
                                float(0.4 * std::cos(theta)), float(0.5 * std::sin(theta) * std::sin(phi))};
            packed.insert(packed.end(), v, v + 3);
            padded.insert(padded.end(), {v[0], v[1], v[2], 0.0f});
        }
    for (int r = 0; r < rings; ++r)
        for (int k = 0; k < segments; ++k) {
            const int a = r * segments + k, b = r * segments + (k + 1) % segments;
            indices.insert(indices.end(), {a, a + segments, b, b, a + segments, b + segments});
        }
    // Float vertices in either precision of Bullet (its array constructor takes btScalar).
    const auto floatMesh = [&](const std::vector<float>& v, int stride) {
        btIndexedMesh m;
        m.m_numTriangles = static_cast<int>(indices.size() / 3);
        m.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(indices.data());
        m.m_triangleIndexStride = 3 * sizeof(int);
        m.m_numVertices = static_cast<int>(packed.size() / 3);
        m.m_vertexBase = reinterpret_cast<const unsigned char*>(v.data());
        m.m_vertexStride = stride;
        m.m_vertexType = PHY_FLOAT;
        auto array = std::make_unique<btTriangleIndexVertexArray>();
        array->addIndexedMesh(m, PHY_INTEGER);
        return array;
    };
    const auto packedArray = floatMesh(packed, 3 * sizeof(float)), paddedArray = floatMesh(padded, 4 * sizeof(float));
    btGImpactMeshShape packedShape(packedArray.get()), paddedShape(paddedArray.get());
    for (btGImpactMeshShape* shape : {&packedShape, &paddedShape}) {
        shape->setLocalScaling(btVector3(1.3f, 0.7f, 1.1f));
        shape->updateBound();
    }
    const btStaticPlaneShape plane(btVector3(0.2f, 1, -0.1f).normalized(), btScalar(0.3));
    std::size_t points = 0, tested = 0;
    for (int pose = 0; pose < 300; ++pose) {
        const btTransform t(btQuaternion(btVector3(btScalar(unit(rng)), btScalar(unit(rng)), btScalar(unit(rng)))
                                             .normalized(),
                                         btScalar(3 * unit(rng))),
                            btVector3(btScalar(unit(rng)), btScalar(0.3 + 0.5 * unit(rng)), btScalar(unit(rng))));
        const btVector4 equation = bullet::planeEquation(plane, btTransform::getIdentity());
        std::vector<btScalar> got[2];
        bullet::PlaneCounts counts[2];
        for (int way = 0; way < 2; ++way) {
            const btGImpactMeshShape& shape = way == 0 ? packedShape : paddedShape;
            bullet::planePartContacts(
                *shape.getMeshPart(0), t, equation, plane.getMargin(),
                [&](const btVector3& v, btScalar d) { got[way].insert(got[way].end(), {v[0], v[1], v[2], d}); },
                counts[way]);
        }
        ASSERT_EQ(got[0].size(), got[1].size()) << "pose " << pose;
        if (!got[0].empty()) {  // (memcmp takes no null pointer, which an empty vector may give)
            EXPECT_EQ(std::memcmp(got[0].data(), got[1].data(), got[0].size() * sizeof(btScalar)), 0) << "pose " << pose;
        }
        EXPECT_EQ(counts[0].tested, counts[1].tested) << "pose " << pose;
        points += got[0].size() / 4;
        tested += counts[0].tested;
    }
    EXPECT_GT(points, 1000u) << "the poses put the mesh across the plane";
    EXPECT_GE(tested, points);
}

/// A mesh deformed every step while it rests on the plane: `factor` gives its size (from its shape as made) step by
/// step; `refit`: postUpdate + updateBound after each change, as Bullet asks. Returns the first step whose states
/// differ in any bit (or -1) and the swap's stats.
int deformOnPlane(const std::function<double(int)>& factor, int steps, bool refit, CullideDispatchStats& stats) {
    ShapeStore shapes;
    OwnMesh blob;
    blob.addEllipsoid(btVector3(0.3f, 0.25f, 0.3f), btVector3(0, 0, 0), 16, 24, false, 1);
    btCollisionShape* shape = blob.finish(btScalar(0.01));
    btCollisionShape* ground = shapes.plane(btVector3(0, 1, 0), btScalar(0));
    TestWorld reference(PipelineKind::Default);
    TestWorld swap(PipelineKind::Cullide, referenceFactory());
    for (TestWorld* w : {&reference, &swap}) {
        btGImpactCollisionAlgorithm::registerAlgorithm(&w->dispatcher());
        w->addBody(ground, 0, at(0, 0, 0));
        w->addBody(shape, 1, at(0, 0.5, 0, btQuaternion(btVector3(1, 0, 0), btScalar(0.3))));
    }
    int differing = -1;
    for (int step = 0; step < steps && differing < 0; ++step) {
        blob.scaleFromRest(factor(step), refit);  // the shape is both worlds'
        if (firstDifferingStep(reference, swap, 1) >= 0) differing = step;
    }
    stats = swap.cullideDispatcher()->getTotalStats();
    return differing;
}

TEST(GImpactPlane, DeformingMeshesKeepBulletsContactsBitForBit) {
    for (const bool refit : {true, false}) {
        CullideDispatchStats stats;
        EXPECT_EQ(deformOnPlane([](int step) { return 1.0 + 0.15 * std::sin(0.2 * step); }, 200, refit, stats), -1)
            << (refit ? "refitted" : "not refitted");
        EXPECT_GT(stats.planePairs, 150u);
        EXPECT_LT(stats.planeVerticesTested, stats.planeVertices / 3) << "most vertices are ruled out";
    }
}

/// Bullet's distance of a vertex: its arithmetic as gimpacttrimeshpart_vs_plane_collision does it.
btScalar bulletDistance(const btVector3& stored, const btVector3& scaling, const btTransform& t,
                        const btVector4& equation, btScalar margin) {
    btVector3 vertex(stored[0] * scaling[0], stored[1] * scaling[1], stored[2] * scaling[2]);
    vertex = t(vertex);
    return vertex.dot(equation) - equation[3] - margin;
}

/// Vertices a hair from the plane, in poses and scalings far from the origin and from 1: wherever Bullet's float
/// (or double) arithmetic puts a vertex below the plane, the filter must let it through, though the exact distance
/// may be just above it. It must also rule out most vertices farther away.
TEST(GImpactPlane, TheFilterNeverRulesOutAVertexBulletPutsBelowThePlane) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(-1, 1);
    std::size_t below = 0, nearButAbove = 0, ruledOutFar = 0, far = 0;
    for (int pose = 0; pose < 200; ++pose) {
        const btQuaternion q(btVector3(btScalar(unit(rng)), btScalar(unit(rng)), btScalar(unit(rng))).normalized(),
                             btScalar(3 * unit(rng)));
        const btTransform t(q, btVector3(btScalar(900 * unit(rng)), btScalar(900 * unit(rng)),
                                         btScalar(900 * unit(rng))));
        const btVector3 scaling(btScalar(1 + 2.5 * std::fabs(unit(rng))), btScalar(0.3 + std::fabs(unit(rng))),
                                btScalar(1.7));
        const btStaticPlaneShape shape(btVector3(btScalar(unit(rng)), 1, btScalar(unit(rng))).normalized(),
                                       btScalar(400 * unit(rng)));
        const btTransform planeAt(btQuaternion(btVector3(0, 1, 0), btScalar(unit(rng))),
                                  btVector3(btScalar(50 * unit(rng)), 0, btScalar(50 * unit(rng))));
        const btVector4 equation = bullet::planeEquation(shape, planeAt);
        const btScalar margin = btScalar(0.05);
        const bullet::PlaneFilter filter(t, scaling, equation, margin);
        const btTransform inverse = t.inverse();
        const btVector3 normal(equation[0], equation[1], equation[2]);
        for (int k = 0; k < 500; ++k) {
            // A point on the plane's margin surface, nudged by a few float steps of the world coordinates, taken
            // back into stored coordinates.
            const btVector3 onPlane = normal * (equation[3] + margin) +
                                      btVector3(btScalar(300 * unit(rng)), btScalar(300 * unit(rng)),
                                                btScalar(300 * unit(rng))).cross(normal);
            const double nudge = (k < 450 ? 4e-4 : 2.0) * unit(rng);
            const btVector3 local = inverse(onPlane + normal * btScalar(nudge));
            const btVector3 stored(local[0] / scaling[0], local[1] / scaling[1], local[2] / scaling[2]);
            const bool passes = filter.mayTouch(stored[0], stored[1], stored[2]);
            if (bulletDistance(stored, scaling, t, equation, margin) < 0.0) {
                ++below;
                EXPECT_TRUE(passes) << "pose " << pose << ", vertex " << k;
            } else if (k < 450) {
                ++nearButAbove;
            } else {
                ++far;
                if (!passes) ++ruledOutFar;
            }
        }
    }
    std::printf("[ measure  ] %zu vertices below the plane, %zu a hair above, %zu of %zu far ones ruled out\n", below,
                nearButAbove, ruledOutFar, far);
    EXPECT_GT(below, 10000u);
    EXPECT_GT(nearButAbove, 10000u);
    EXPECT_GT(ruledOutFar, far * 9 / 10);
}

}  // namespace
}  // namespace cullide::test
