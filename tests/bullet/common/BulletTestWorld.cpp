#include "BulletTestWorld.h"
#include "cullide/Timer.h"

#include "cullide/Culler.h"

#include <BulletCollision/CollisionShapes/btConvexTriangleMeshShape.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace cullide::test {
namespace {


/// Times a broadphase's work of one step: every setAabb since the last calculateOverlappingPairs (btDbvtBroadphase
/// finds most pairs there) plus calculateOverlappingPairs itself.
template <class Base>
class TimedBroadphase final : public Base {
public:
    using Base::Base;
    void setAabb(btBroadphaseProxy* proxy, const btVector3& aabbMin, const btVector3& aabbMax,
                 btDispatcher* dispatcher) override {
        cullide::Timer w;
        Base::setAabb(proxy, aabbMin, aabbMax, dispatcher);
        m_setAabbMs += w.ms();
    }
    void calculateOverlappingPairs(btDispatcher* dispatcher) override {
        cullide::Timer w;
        Base::calculateOverlappingPairs(dispatcher);
        lastMs = w.ms() + m_setAabbMs;
        m_setAabbMs = 0.0;
    }
    double lastMs = 0.0;

private:
    double m_setAabbMs = 0.0;
};

/// Times dispatchAllCollisionPairs on the world's own pair cache.
template <class Base>
class TimedDispatcher final : public Base {
public:
    using Base::Base;
    void dispatchAllCollisionPairs(btOverlappingPairCache* cache, const btDispatcherInfo& info,
                                   btDispatcher* dispatcher) override {
        cullide::Timer w;
        Base::dispatchAllCollisionPairs(cache, info, dispatcher);
        if (cache == worldCache) {
            lastMs = w.ms();
            lastPairs = static_cast<std::size_t>(cache->getNumOverlappingPairs());
        }
    }
    const btOverlappingPairCache* worldCache = nullptr;
    double lastMs = 0.0;
    std::size_t lastPairs = 0;
};

using DefaultBroadphase = TimedBroadphase<btDbvtBroadphase>;
using DefaultDispatcher = TimedDispatcher<btCollisionDispatcher>;
using CullideBp = TimedBroadphase<CullideBroadphase>;
using CullideDisp = TimedDispatcher<CullideCollisionDispatcher>;

}  // namespace

// ---------------------------------------------------------------------------------------------------------------

struct ShapeStore::Mesh {
    std::vector<btScalar> vertices;
    std::vector<int> indices;
    std::unique_ptr<btTriangleIndexVertexArray> array;

    void finish() {
        array = std::make_unique<btTriangleIndexVertexArray>(
            static_cast<int>(indices.size() / 3), indices.data(), static_cast<int>(3 * sizeof(int)),
            static_cast<int>(vertices.size() / 3), vertices.data(), static_cast<int>(3 * sizeof(btScalar)));
    }
};

ShapeStore::ShapeStore() = default;
ShapeStore::~ShapeStore() {
    m_shapes.clear();  // shapes reference the meshes
    m_meshes.clear();
}

btCollisionShape* ShapeStore::box(const btVector3& halfExtents) {
    m_shapes.push_back(std::make_unique<btBoxShape>(halfExtents));
    return m_shapes.back().get();
}

btCollisionShape* ShapeStore::sphere(btScalar radius) {
    m_shapes.push_back(std::make_unique<btSphereShape>(radius));
    return m_shapes.back().get();
}

btCollisionShape* ShapeStore::capsule(btScalar radius, btScalar height) {
    m_shapes.push_back(std::make_unique<btCapsuleShape>(radius, height));
    return m_shapes.back().get();
}

btCollisionShape* ShapeStore::hull(const btVector3& radii, int points, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    auto shape = std::make_unique<btConvexHullShape>();
    for (int i = 0; i < points; ++i) {
        btVector3 d;
        do {
            d.setValue(btScalar(u(rng)), btScalar(u(rng)), btScalar(u(rng)));
        } while (d.length2() < btScalar(0.05) || d.length2() > btScalar(1));
        d.normalize();
        shape->addPoint(d * radii, false);
    }
    shape->recalcLocalAabb();
    m_shapes.push_back(std::move(shape));
    return m_shapes.back().get();
}

namespace {
/// An application's own vertex-array class (Bullet's, derived): the adapter cannot know that its locks are safe.
struct OwnVertexArray final : btTriangleIndexVertexArray {
    using btTriangleIndexVertexArray::btTriangleIndexVertexArray;
};
}  // namespace

btCollisionShape* ShapeStore::convexMesh(const btVector3& radii, int rings, int segments, bool ownInterface) {
    auto mesh = std::make_unique<Mesh>();
    const double pi = 3.141592653589793;
    const auto vertex = [&](int ring, int segment) {
        const double theta = pi * ring / rings, phi = 2 * pi * segment / segments;
        mesh->vertices.insert(mesh->vertices.end(), {btScalar(radii.x() * std::sin(theta) * std::cos(phi)),
                                                     btScalar(radii.y() * std::cos(theta)),
                                                     btScalar(radii.z() * std::sin(theta) * std::sin(phi))});
    };
    for (int ring = 0; ring <= rings; ++ring)
        for (int segment = 0; segment < segments; ++segment) vertex(ring, segment);
    for (int ring = 0; ring < rings; ++ring)
        for (int segment = 0; segment < segments; ++segment) {
            const int a = ring * segments + segment, b = ring * segments + (segment + 1) % segments;
            const int c = a + segments, d = b + segments;
            mesh->indices.insert(mesh->indices.end(), {a, c, b, b, c, d});
        }
    if (ownInterface)
        mesh->array = std::make_unique<OwnVertexArray>(
            static_cast<int>(mesh->indices.size() / 3), mesh->indices.data(), static_cast<int>(3 * sizeof(int)),
            static_cast<int>(mesh->vertices.size() / 3), mesh->vertices.data(), static_cast<int>(3 * sizeof(btScalar)));
    else
        mesh->finish();
    m_shapes.push_back(std::make_unique<btConvexTriangleMeshShape>(mesh->array.get()));
    m_meshes.push_back(std::move(mesh));
    return m_shapes.back().get();
}

btCollisionShape* ShapeStore::landscape(int cells, btScalar cellSize, btScalar amplitude) {
    auto mesh = std::make_unique<Mesh>();
    const int n = cells + 1;
    const btScalar half = btScalar(cells) * cellSize / 2;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const btScalar x = btScalar(i) * cellSize - half;
            const btScalar z = btScalar(j) * cellSize - half;
            const btScalar y = amplitude * (std::sin(x * btScalar(0.35)) * std::cos(z * btScalar(0.27)) +
                                            btScalar(0.3) * std::sin(btScalar(0.9) * x + btScalar(0.6) * z));
            mesh->vertices.insert(mesh->vertices.end(), {x, y, z});
        }
    for (int j = 0; j < cells; ++j)
        for (int i = 0; i < cells; ++i) {
            const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
            mesh->indices.insert(mesh->indices.end(), {a, c, b, b, c, d});
        }
    mesh->finish();
    m_shapes.push_back(std::make_unique<btBvhTriangleMeshShape>(mesh->array.get(), true));
    m_meshes.push_back(std::move(mesh));
    return m_shapes.back().get();
}

btCollisionShape* ShapeStore::gimpactTorus(btScalar R, btScalar r, int segments, int sides, btScalar margin,
                                           const btVector3& centre) {
    auto mesh = std::make_unique<Mesh>();
    const double twoPi = 6.283185307179586;
    for (int s = 0; s < segments; ++s)
        for (int t = 0; t < sides; ++t) {
            const double u = twoPi * s / segments, v = twoPi * t / sides;
            const double x = (R + r * std::cos(v)) * std::cos(u);
            const double y = r * std::sin(v);
            const double z = (R + r * std::cos(v)) * std::sin(u);
            mesh->vertices.insert(mesh->vertices.end(),
                                  {btScalar(x) + centre.x(), btScalar(y) + centre.y(), btScalar(z) + centre.z()});
        }
    for (int s = 0; s < segments; ++s)
        for (int t = 0; t < sides; ++t) {
            const int a = s * sides + t;
            const int b = s * sides + (t + 1) % sides;
            const int c = ((s + 1) % segments) * sides + t;
            const int d = ((s + 1) % segments) * sides + (t + 1) % sides;
            mesh->indices.insert(mesh->indices.end(), {a, b, c, b, d, c});
        }
    mesh->finish();
    auto shape = std::make_unique<btGImpactMeshShape>(mesh->array.get());
    shape->setMargin(margin);
    shape->updateBound();
    m_shapes.push_back(std::move(shape));
    m_meshes.push_back(std::move(mesh));
    return m_shapes.back().get();
}

btCollisionShape* ShapeStore::plane(const btVector3& normal, btScalar constant) {
    m_shapes.push_back(std::make_unique<btStaticPlaneShape>(normal, constant));
    return m_shapes.back().get();
}

// ---------------------------------------------------------------------------------------------------------------

class TestWorld::World final : public btDiscreteDynamicsWorld {
public:
    World(TestWorld& owner, btDispatcher* d, btBroadphaseInterface* b, btConstraintSolver* s,
          btCollisionConfiguration* c)
        : btDiscreteDynamicsWorld(d, b, s, c), m_owner(owner) {}

    /// What internalSingleStepSimulation does before solving: unconstrained motion (the swept AABBs of continuous
    /// collision), CCD's predictive contacts, collision detection.
    void detectCollisionsOfAStep(btScalar dt) {
        predictUnconstraintMotion(dt);
        getDispatchInfo().m_timeStep = dt;
        getDispatchInfo().m_stepCount = 0;
        createPredictiveContacts(dt);
        performDiscreteCollisionDetection();
    }

protected:
    void solveConstraints(btContactSolverInfo& info) override {
        btDiscreteDynamicsWorld::solveConstraints(info);
        if (m_owner.midStep) m_owner.midStep(m_owner);
    }

private:
    TestWorld& m_owner;
};

CollisionOnlyWorld::CollisionOnlyWorld(PipelineKind kind) : m_config(std::make_unique<btDefaultCollisionConfiguration>()) {
    if (kind == PipelineKind::Default) {
        m_broadphase = std::make_unique<btDbvtBroadphase>();
        m_dispatcher = std::make_unique<btCollisionDispatcher>(m_config.get());
    } else {
        auto broadphase = std::make_unique<CullideBroadphase>(Settings{}, nullptr, referenceFactory());
        m_dispatcher = std::make_unique<CullideCollisionDispatcher>(m_config.get(), broadphase.get());
        m_broadphase = std::move(broadphase);
    }
    btGImpactCollisionAlgorithm::registerAlgorithm(m_dispatcher.get());
    m_world = std::make_unique<btCollisionWorld>(m_dispatcher.get(), m_broadphase.get(), m_config.get());
}

CollisionOnlyWorld::~CollisionOnlyWorld() {
    for (auto& o : m_objects) m_world->removeCollisionObject(o.get());
}

btCollisionObject* CollisionOnlyWorld::add(btCollisionShape* shape, const btTransform& t, int group, int mask) {
    auto o = std::make_unique<btCollisionObject>();  // CF_STATIC_OBJECT, ACTIVE_TAG: Bullet's defaults
    o->setCollisionShape(shape);
    o->setWorldTransform(t);
    o->setUserIndex(static_cast<int>(m_objects.size()));
    m_world->addCollisionObject(o.get(), group, mask);
    m_objects.push_back(std::move(o));
    return m_objects.back().get();
}

TestWorld::TestWorld(PipelineKind kind, CullideBroadphase::CullerFactory factory, const Settings& settings)
    : m_kind(kind), m_config(std::make_unique<btDefaultCollisionConfiguration>()) {
    if (kind == PipelineKind::Default) {
        auto bp = std::make_unique<DefaultBroadphase>();
        auto disp = std::make_unique<DefaultDispatcher>(m_config.get());
        disp->worldCache = bp->getOverlappingPairCache();
        m_broadphase = std::move(bp);
        m_dispatcher = std::move(disp);
    } else {
        auto bp = std::make_unique<CullideBp>(settings, nullptr, factory ? factory : gpuFactory());
        auto disp = std::make_unique<CullideDisp>(m_config.get(), bp.get());
        disp->worldCache = bp->getOverlappingPairCache();
        m_cullideBroadphase = bp.get();
        m_cullideDispatcher = disp.get();
        m_broadphase = std::move(bp);
        m_dispatcher = std::move(disp);
    }
    m_solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    m_world = std::make_unique<World>(*this, m_dispatcher.get(), m_broadphase.get(), m_solver.get(), m_config.get());
    m_world->setGravity(btVector3(0, -9.81f, 0));
}

TestWorld::~TestWorld() {
    for (int i = m_world->getNumCollisionObjects() - 1; i >= 0; --i)
        m_world->removeCollisionObject(m_world->getCollisionObjectArray()[i]);
    m_world.reset();
    m_solver.reset();
    m_broadphase.reset();
    m_dispatcher.reset();
    m_owned.clear();
    m_config.reset();
}

btRigidBody* TestWorld::addBody(btCollisionShape* shape, btScalar mass, const btTransform& transform, int group,
                                int mask) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape, inertia);
    info.m_startWorldTransform = transform;
    auto body = std::make_unique<btRigidBody>(info);
    btRigidBody* raw = body.get();
    raw->setUserIndex(nextIndex());
    m_objectsByIndex.push_back(raw);
    m_owned.push_back(std::move(body));
    if (group != 0 || mask != 0)
        m_world->addRigidBody(raw, group, mask);
    else
        m_world->addRigidBody(raw);
    return raw;
}

void TestWorld::removeBody(btRigidBody* body) { m_world->removeRigidBody(body); }

btCollisionObject* TestWorld::objectByIndex(int index) const { return m_objectsByIndex.at(std::size_t(index)); }

void TestWorld::adopt(std::unique_ptr<btCollisionObject> object) {
    object->setUserIndex(nextIndex());
    m_objectsByIndex.push_back(object.get());
    m_owned.push_back(std::move(object));
}

void TestWorld::step(btScalar dt) { m_world->stepSimulation(dt, 1, dt); }

void TestWorld::detectCollisions(btScalar dt) { static_cast<World&>(*m_world).detectCollisionsOfAStep(dt); }

double TestWorld::lastBroadphaseMs() const {
    if (m_kind == PipelineKind::Default) return static_cast<const DefaultBroadphase&>(*m_broadphase).lastMs;
    return static_cast<const CullideBp&>(*m_broadphase).lastMs;
}

double TestWorld::lastNarrowPhaseMs() const {
    if (m_kind == PipelineKind::Default) return static_cast<const DefaultDispatcher&>(*m_dispatcher).lastMs;
    return static_cast<const CullideDisp&>(*m_dispatcher).lastMs;
}

std::size_t TestWorld::lastPairCount() const {
    if (m_kind == PipelineKind::Default) return static_cast<const DefaultDispatcher&>(*m_dispatcher).lastPairs;
    return static_cast<const CullideDisp&>(*m_dispatcher).lastPairs;
}

// ---------------------------------------------------------------------------------------------------------------

std::set<std::pair<int, int>> pairsOf(btCollisionWorld& world) {
    std::set<std::pair<int, int>> out;
    btOverlappingPairCache* cache = world.getPairCache();
    for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
        const btBroadphasePair& p = cache->getOverlappingPairArrayPtr()[i];
        const int a = static_cast<btCollisionObject*>(p.m_pProxy0->m_clientObject)->getUserIndex();
        const int b = static_cast<btCollisionObject*>(p.m_pProxy1->m_clientObject)->getUserIndex();
        out.insert({std::min(a, b), std::max(a, b)});
    }
    return out;
}

ContactMap contactsOf(btCollisionWorld& world) {
    ContactMap out;
    btDispatcher* dispatcher = world.getDispatcher();
    for (int i = 0; i < dispatcher->getNumManifolds(); ++i) {
        const btPersistentManifold* m = dispatcher->getManifoldByIndexInternal(i);
        if (m->getNumContacts() == 0) continue;
        const int a = m->getBody0()->getUserIndex();
        const int b = m->getBody1()->getUserIndex();
        const bool swap = a > b;
        PairContacts& pc = out[{std::min(a, b), std::max(a, b)}];
        for (int k = 0; k < m->getNumContacts(); ++k) {
            const btManifoldPoint& pt = m->getContactPoint(k);
            ++pc.points;
            pc.minDistance = std::min(pc.minDistance, double(pt.getDistance()));
            pc.positionsOnB.push_back(swap ? pt.getPositionWorldOnA() : pt.getPositionWorldOnB());
            pc.normalsOnB.push_back(swap ? -pt.m_normalWorldOnB : pt.m_normalWorldOnB);
            pc.distances.push_back(double(pt.getDistance()));
        }
    }
    return out;
}

void mirrorState(TestWorld& from, TestWorld& to) {
    const auto& a = from.objects();
    const auto& b = to.objects();
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
        btRigidBody* ra = btRigidBody::upcast(a[i]);
        btRigidBody* rb = btRigidBody::upcast(b[i]);
        if (ra == nullptr || rb == nullptr) continue;
        rb->setWorldTransform(ra->getWorldTransform());
        rb->setInterpolationWorldTransform(ra->getInterpolationWorldTransform());
        rb->setLinearVelocity(ra->getLinearVelocity());
        rb->setAngularVelocity(ra->getAngularVelocity());
        rb->setInterpolationLinearVelocity(ra->getInterpolationLinearVelocity());
        rb->setInterpolationAngularVelocity(ra->getInterpolationAngularVelocity());
        rb->forceActivationState(ra->getActivationState());
        rb->setDeactivationTime(ra->getDeactivationTime());
    }
}

void ContactAgreement::add(const ContactMap& reference, const ContactMap& other,
                           const std::function<double(const std::pair<int, int>&)>& tolerance) {
    for (const auto& [key, ref] : reference) {
        ++referencePairs;
        const auto it = other.find(key);
        if (it == other.end()) {
            ++missingPairs;
            if (firstMissing.empty()) {
                char buf[160];
                std::snprintf(buf, sizeof buf, "pair (%d, %d) with %d points, min distance %.5f", key.first,
                              key.second, ref.points, ref.minDistance);
                firstMissing = buf;
            }
            continue;
        }
        ++comparedPairs;
        if (tolerance(key) <= kExactTolerance) {
            // Same algorithm, same input: every reference point has a twin.
            ++pointComparedPairs;
            const PairContacts& oth = it->second;
            for (std::size_t i = 0; i < ref.positionsOnB.size(); ++i) {
                bool twin = false;
                for (std::size_t j = 0; j < oth.positionsOnB.size() && !twin; ++j)
                    twin = (ref.positionsOnB[i] - oth.positionsOnB[j]).length() <= btScalar(kExactTolerance) &&
                           (ref.normalsOnB[i] - oth.normalsOnB[j]).length() <= btScalar(kExactTolerance) &&
                           std::fabs(ref.distances[i] - oth.distances[j]) <= kExactTolerance;
                if (!twin) ++pointMismatches;
            }
        }
        const double diff = std::fabs(ref.minDistance - it->second.minDistance);
        maxDepthDifference = std::max(maxDepthDifference, diff);
        if (diff > tolerance(key)) {
            ++depthMismatches;
            if (std::getenv("CULLIDE_BULLET_DEBUG") != nullptr)
                std::printf("  mismatch pair (%d,%d): ref %d pts min %.5f, other %d pts min %.5f\n", key.first,
                            key.second, ref.points, ref.minDistance, it->second.points, it->second.minDistance);
        }
    }
    for (const auto& [key, pc] : other)
        if (reference.find(key) == reference.end()) ++extraPairs;
}

std::string StepTimes::summary(const char* name) const {
    char buf[200];
    const double n = steps > 0 ? double(steps) : 1.0;
    std::snprintf(buf, sizeof buf, "%-8s broadphase %7.3f ms/step, narrow phase %7.3f ms/step, %7.1f pairs/step",
                  name, broadphaseMs / n, narrowMs / n, double(pairs) / n);
    return buf;
}

CullideBroadphase::CullerFactory gpuFactory() {
    return [](const Settings& s) { return createGpuCuller(s); };
}

CullideBroadphase::CullerFactory referenceFactory() {
    return [](const Settings& s) { return createReferenceCuller(s); };
}

}  // namespace cullide::test
