#include "BulletEngine.h"
#include "BulletMesh.h"

#include "cullide/Timer.h"

#include <BulletCollision/CollisionDispatch/btManifoldResult.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletCollisionCommon.h>

#include <array>
#include <cstdint>
#include <vector>

namespace cullide::bench {

namespace {

/// Contact points recorded by the callback: (object, triangle, object, triangle).
std::vector<TriangleKey>* g_contactSink = nullptr;

bool recordContact(btManifoldPoint&, const btCollisionObjectWrapper* w0, int, int index0,
                   const btCollisionObjectWrapper* w1, int, int index1) {
    if (g_contactSink != nullptr)
        g_contactSink->push_back({static_cast<std::uint32_t>(w0->getCollisionObject()->getUserIndex()),
                                  static_cast<std::uint32_t>(index0),
                                  static_cast<std::uint32_t>(w1->getCollisionObject()->getUserIndex()),
                                  static_cast<std::uint32_t>(index1)});
    return false;
}

}  // namespace

struct BulletEngine::Impl {
    Broadphase kind;
    std::unique_ptr<btDefaultCollisionConfiguration> config;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionWorld> world;
    std::vector<GImpactBody> bodies;
    std::vector<TriangleKey> contacts;

    ~Impl() {
        if (world)
            for (GImpactBody& b : bodies)
                if (b.object) world->removeCollisionObject(b.object.get());
        if (g_contactSink == &contacts) g_contactSink = nullptr;
    }
};

BulletEngine::BulletEngine(Broadphase broadphase) : m_impl(std::make_unique<Impl>()) { m_impl->kind = broadphase; }

BulletEngine::~BulletEngine() = default;

void BulletEngine::setup(const BenchFrame& first) {
    Impl& m = *m_impl;
    m.config = std::make_unique<btDefaultCollisionConfiguration>();
    m.dispatcher = std::make_unique<btCollisionDispatcher>(m.config.get());
    btGImpactCollisionAlgorithm::registerAlgorithm(m.dispatcher.get());
    if (m.kind == Broadphase::Dbvt) {
        m.broadphase = std::make_unique<btDbvtBroadphase>();
    } else {
        // World bounds for the sweep: the first frame's bounds, grown to three times their size (the environments
        // keep their objects inside a fixed box).
        Aabb box;
        for (const auto& mesh : *first.world)
            for (const Vec3& p : mesh.vertices) box.grow(p);
        const Vec3 centre = 0.5 * (box.min + box.max);
        const double half = 1.5 * box.extent().maxCoeff() + 1.0;
        const auto v = [](const Vec3& p) {
            return btVector3(static_cast<btScalar>(p.x()), static_cast<btScalar>(p.y()), static_cast<btScalar>(p.z()));
        };
        m.broadphase = std::make_unique<btAxisSweep3>(v(centre - Vec3::Constant(half)), v(centre + Vec3::Constant(half)),
                                                      static_cast<unsigned short>(16384));
    }
    m.world = std::make_unique<btCollisionWorld>(m.dispatcher.get(), m.broadphase.get(), m.config.get());
    gContactAddedCallback = recordContact;
    g_contactSink = &m.contacts;

    const auto& meshes = *first.local;
    m.bodies.resize(meshes.size());
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        GImpactBody& b = m.bodies[i];
        b.build(first, i);
        int flags = b.object->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK;
        if (b.motion == Motion::Static) flags |= btCollisionObject::CF_STATIC_OBJECT;
        b.object->setCollisionFlags(flags);
        m.world->addCollisionObject(b.object.get());
    }
}

void BulletEngine::run(const BenchFrame& frame, FrameOutput& out) {
    Impl& m = *m_impl;
    out.clear();
    m.contacts.clear();
    const Timer total;
    Timer stage;
    for (std::size_t i = 0; i < m.bodies.size(); ++i) m.bodies[i].move(frame, i);
    out.stages.push_back({"refit", stage.ms()});
    stage = Timer();
    m.world->updateAabbs();
    out.stages.push_back({"aabbs", stage.ms()});
    stage = Timer();
    m.world->computeOverlappingPairs();
    out.stages.push_back({"broadphase", stage.ms()});
    stage = Timer();
    m.dispatcher->dispatchAllCollisionPairs(m.broadphase->getOverlappingPairCache(), m.world->getDispatchInfo(),
                                            m.dispatcher.get());
    out.stages.push_back({"narrow phase", stage.ms()});
    out.totalMs = total.ms();
    for (int k = 0; k < m.dispatcher->getNumManifolds(); ++k)
        out.contacts += static_cast<std::size_t>(m.dispatcher->getManifoldByIndexInternal(k)->getNumContacts());
    for (const TriangleKey& c : m.contacts) out.pairs.addTriangle(c[0], c[1], c[2], c[3]);
    out.pairs.finish();
}

nlohmann::json BulletEngine::describe() const {
    nlohmann::json j;
    j["mode"] = "gimpact";
    j["broadphase"] = m_impl->kind == Broadphase::Dbvt ? "btDbvtBroadphase" : "btAxisSweep3";
    j["threads"] = 1;
    j["btScalar_bytes"] = sizeof(btScalar);
    return j;
}

}  // namespace cullide::bench
