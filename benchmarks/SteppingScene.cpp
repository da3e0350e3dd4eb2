#include "SteppingScene.h"

#include "SeededRandom.h"
#include "cullide/Timer.h"
#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace cullide::bench {

namespace {

/// A dynamics world that times the three parts of its collision detection.
class TimedWorld final : public btDiscreteDynamicsWorld {
public:
    using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;

    void performDiscreteCollisionDetection() override {
        Timer t;
        updateAabbs();
        aabbMs = t.ms();
        t = Timer();
        computeOverlappingPairs();
        broadphaseMs = t.ms();
        t = Timer();
        if (btDispatcher* d = getDispatcher())
            d->dispatchAllCollisionPairs(getBroadphase()->getOverlappingPairCache(), getDispatchInfo(), d);
        narrowMs = t.ms();
    }

    double aabbMs = 0, broadphaseMs = 0, narrowMs = 0;
};

using Random = cullide::bench::SeededRandom;

}  // namespace

struct SteppingScene::Impl {
    std::string scene, engine;
    std::unique_ptr<btDefaultCollisionConfiguration> config;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    CullideBroadphase* cullide = nullptr;
    std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
    std::unique_ptr<TimedWorld> world;
    std::vector<std::unique_ptr<btCollisionShape>> shapes;
    std::vector<std::unique_ptr<btRigidBody>> bodies;
    std::vector<std::unique_ptr<btDefaultMotionState>> motionStates;
    std::vector<btScalar> landscapeVertices;
    std::vector<int> landscapeIndices;
    std::unique_ptr<btTriangleIndexVertexArray> landscapeArray;
    std::size_t triangles = 0;

    btRigidBody* add(btCollisionShape* shape, btScalar mass, const btVector3& origin) {
        btVector3 inertia(0, 0, 0);
        if (mass > 0) shape->calculateLocalInertia(mass, inertia);
        btTransform t;
        t.setIdentity();
        t.setOrigin(origin);
        motionStates.push_back(std::make_unique<btDefaultMotionState>(t));
        btRigidBody::btRigidBodyConstructionInfo info(mass, motionStates.back().get(), shape, inertia);
        bodies.push_back(std::make_unique<btRigidBody>(info));
        bodies.back()->setUserIndex(static_cast<int>(bodies.size() - 1));
        world->addRigidBody(bodies.back().get());
        return bodies.back().get();
    }

    btCollisionShape* own(btCollisionShape* shape) {
        shapes.emplace_back(shape);
        return shape;
    }

    void buildStack() {
        btCollisionShape* ground = own(new btBoxShape(btVector3(20, 1, 20)));
        add(ground, 0, btVector3(0, -1, 0));
        btCollisionShape* box = own(new btBoxShape(btVector3(btScalar(0.5), btScalar(0.5), btScalar(0.5))));
        const int levels = 10;
        for (int level = 0; level < levels; ++level)
            for (int i = 0; i < levels - level; ++i)
                add(box, 1, btVector3(btScalar(i - 0.5 * (levels - level - 1)) * btScalar(1.02),
                                      btScalar(0.5 + level), 0));
        triangles = 12 * bodies.size();
    }

    void buildLandscape() {
        const int cells = 64;
        const btScalar cell = 1, amplitude = 2;
        for (int z = 0; z <= cells; ++z)
            for (int x = 0; x <= cells; ++x) {
                const double fx = x * 0.21, fz = z * 0.17;
                const double h = amplitude * (0.5 * std::sin(fx) * std::cos(fz) + 0.25 * std::sin(2.3 * fx + 1.1 * fz));
                landscapeVertices.push_back((btScalar(x) - btScalar(cells) / 2) * cell);
                landscapeVertices.push_back(static_cast<btScalar>(h));
                landscapeVertices.push_back((btScalar(z) - btScalar(cells) / 2) * cell);
            }
        for (int z = 0; z < cells; ++z)
            for (int x = 0; x < cells; ++x) {
                const int v = z * (cells + 1) + x;
                for (int k : {v, v + cells + 1, v + 1, v + 1, v + cells + 1, v + cells + 2}) landscapeIndices.push_back(k);
            }
        btIndexedMesh part;
        part.m_numTriangles = static_cast<int>(landscapeIndices.size() / 3);
        part.m_triangleIndexBase = reinterpret_cast<const unsigned char*>(landscapeIndices.data());
        part.m_triangleIndexStride = 3 * static_cast<int>(sizeof(int));
        part.m_numVertices = static_cast<int>(landscapeVertices.size() / 3);
        part.m_vertexBase = reinterpret_cast<const unsigned char*>(landscapeVertices.data());
        part.m_vertexStride = 3 * static_cast<int>(sizeof(btScalar));
        landscapeArray = std::make_unique<btTriangleIndexVertexArray>();
        landscapeArray->addIndexedMesh(part, PHY_INTEGER);
        add(own(new btBvhTriangleMeshShape(landscapeArray.get(), true)), 0, btVector3(0, 0, 0));
        triangles = static_cast<std::size_t>(part.m_numTriangles);

        Random rng(7);
        std::vector<btCollisionShape*> kinds;
        kinds.push_back(own(new btSphereShape(btScalar(0.4))));
        kinds.push_back(own(new btBoxShape(btVector3(btScalar(0.4), btScalar(0.3), btScalar(0.35)))));
        kinds.push_back(own(new btCapsuleShape(btScalar(0.25), btScalar(0.6))));
        for (int h = 0; h < 3; ++h) {  // irregular convex hulls of 24 points
            auto* hull = new btConvexHullShape();
            for (int p = 0; p < 24; ++p)
                hull->addPoint(btVector3(rng.uniform(-0.5, 0.5), rng.uniform(-0.4, 0.4), rng.uniform(-0.45, 0.45)),
                               p == 23);
            kinds.push_back(own(hull));
        }
        const int count = 150;
        for (int i = 0; i < count; ++i) {
            const btScalar x = rng.uniform(-24, 24), z = rng.uniform(-24, 24), y = rng.uniform(4, 10);
            add(kinds[static_cast<std::size_t>(i) % kinds.size()], 1, btVector3(x, y, z));
        }
    }
};

SteppingScene::SteppingScene(const std::string& scene, const std::string& engine) : m_impl(std::make_unique<Impl>()) {
    Impl& m = *m_impl;
    m.scene = scene;
    m.engine = engine;
    if (scene != "stack" && scene != "landscape")
        throw std::invalid_argument("unknown stepping scene '" + scene + "' (stack, landscape)");
    m.config = std::make_unique<btDefaultCollisionConfiguration>();
    if (engine == "cullide") {
        auto bp = std::make_unique<CullideBroadphase>();
        m.cullide = bp.get();
        m.dispatcher = std::make_unique<CullideCollisionDispatcher>(m.config.get(), bp.get());
        m.broadphase = std::move(bp);
    } else if (engine == "bullet-dbvt" || engine == "bullet-sap") {
        m.dispatcher = std::make_unique<btCollisionDispatcher>(m.config.get());
        if (engine == "bullet-dbvt")
            m.broadphase = std::make_unique<btDbvtBroadphase>();
        else
            m.broadphase = std::make_unique<btAxisSweep3>(btVector3(-100, -100, -100), btVector3(100, 100, 100));
    } else {
        throw std::invalid_argument("engine '" + engine + "' does not run stepping scenes (cullide, bullet-dbvt, "
                                    "bullet-sap)");
    }
    m.solver = std::make_unique<btSequentialImpulseConstraintSolver>();
    m.world = std::make_unique<TimedWorld>(m.dispatcher.get(), m.broadphase.get(), m.solver.get(), m.config.get());
    m.world->setGravity(btVector3(0, -10, 0));
    if (scene == "stack")
        m.buildStack();
    else
        m.buildLandscape();
}

SteppingScene::~SteppingScene() {
    Impl& m = *m_impl;
    for (auto& b : m.bodies) m.world->removeRigidBody(b.get());
}

void SteppingScene::step(FrameOutput& out) {
    Impl& m = *m_impl;
    out.clear();
    out.trianglePairsKnown = false;
    const Timer total;
    m.world->stepSimulation(btScalar(1.0 / 60.0), 0);
    out.totalMs = total.ms();
    const double collision = m.world->aabbMs + m.world->broadphaseMs + m.world->narrowMs;
    out.stages = {{"aabbs", m.world->aabbMs},
                  {"broadphase", m.world->broadphaseMs},
                  {"narrow phase", m.world->narrowMs},
                  {"solver", out.totalMs > collision ? out.totalMs - collision : 0.0}};
    for (int k = 0; k < m.dispatcher->getNumManifolds(); ++k) {
        const btPersistentManifold* manifold = m.dispatcher->getManifoldByIndexInternal(k);
        if (manifold->getNumContacts() == 0) continue;
        out.contacts += static_cast<std::size_t>(manifold->getNumContacts());
        out.pairs.addObject(static_cast<std::uint32_t>(manifold->getBody0()->getUserIndex()),
                            static_cast<std::uint32_t>(manifold->getBody1()->getUserIndex()));
    }
    out.pairs.finish();
    if (m.cullide != nullptr) {
        out.bytesUploaded = m.cullide->getLastFrameStats().culler.bytesUploaded;
        out.gpuDeviceBytes = m.cullide->getLastFrameStats().culler.gpuDeviceBytes;
    }
}

nlohmann::json SteppingScene::describe() const {
    const Impl& m = *m_impl;
    nlohmann::json j;
    j["mode"] = m.engine == "cullide" ? "reliable" : "bullet";
    j["broadphase"] = m.engine == "cullide" ? "CullideBroadphase" : m.engine == "bullet-dbvt" ? "btDbvtBroadphase"
                                                                                               : "btAxisSweep3";
    if (m.cullide != nullptr) {
        j["gpu_levels"] = "auto";
        j["resolution"] = m.cullide->getSettings().resolution;
        j["renderer"] = m.cullide->getLastFrameStats().culler.renderer;
        j["device"] = m.cullide->getLastFrameStats().culler.device;
    }
    return j;
}

std::size_t SteppingScene::objectCount() const { return m_impl->bodies.size(); }

std::size_t SteppingScene::triangleCount() const { return m_impl->triangles; }

}  // namespace cullide::bench
