#include "cullide/demo/BreakableScene.h"

#include "cullide/Timer.h"
#include "cullide/demo/Fracture.h"
#include "cullide/io/MeshIO.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace cullide::demo {

namespace {

constexpr double kDt = 1.0 / 60.0;
constexpr double kDragonSize = 2.0;   // largest extent of the breakable object (m)
constexpr double kFallingSize = 0.9;  // largest extent of the falling object (m)
constexpr double kDensity = 400.0;    // kg/m^3 (solid hulls: light wood)
constexpr double kGapFraction = 2e-3; // pieces start this fraction of the breakable's size apart
constexpr btScalar kMargin = btScalar(0.004);

/// Broadphase / dispatcher wrappers that time Bullet's own pipeline like CULLIDE's stats time it.
template <class Base>
class TimedBroadphase final : public Base {
public:
    using Base::Base;
    void calculateOverlappingPairs(btDispatcher* dispatcher) override {
        Timer t;
        Base::calculateOverlappingPairs(dispatcher);
        ms += t.ms();
    }
    double ms = 0.0;
};

class TimedDispatcher final : public btCollisionDispatcher {
public:
    using btCollisionDispatcher::btCollisionDispatcher;
    void dispatchAllCollisionPairs(btOverlappingPairCache* cache, const btDispatcherInfo& info,
                                   btDispatcher* dispatcher) override {
        Timer t;
        btCollisionDispatcher::dispatchAllCollisionPairs(cache, info, dispatcher);
        ms += t.ms();
    }
    double ms = 0.0;
};

/// The vertices some triangle uses (an OBJ may carry others, which must not count for bounds or mass).
std::vector<Vec3> referencedVertices(const TriangleMesh& mesh) {
    std::vector<std::uint8_t> used(mesh.vertices.size(), 0);
    for (const TriangleIndices& t : mesh.triangles)
        for (std::uint32_t v : t)
            if (v < used.size()) used[v] = 1;
    std::vector<Vec3> out;
    for (std::size_t v = 0; v < used.size(); ++v)
        if (used[v] && mesh.vertices[v].allFinite()) out.push_back(mesh.vertices[v]);
    return out;
}

Aabb boundsOf(const std::vector<Vec3>& points) {
    Aabb box;
    for (const Vec3& p : points) box.grow(p);
    return box;
}

/// Scales `mesh` so the largest extent of its triangles is `size` and centres their box at the origin.
void normalize(TriangleMesh& mesh, double size) {
    const Aabb box = boundsOf(referencedVertices(mesh));
    if (box.isEmpty()) throw std::runtime_error("the mesh has no finite triangle");
    const double scale = size / std::max(box.extent().maxCoeff(), 1e-300);
    const Vec3 centre = 0.5 * (box.min + box.max);
    for (Vec3& v : mesh.vertices) v = (v - centre) * scale;
}

TriangleMesh loadMesh(const std::string& path, const std::string& dataDir, scenes::PaperModel model, bool& standIn) {
    if (!path.empty()) {
        TriangleMesh mesh = io::readMesh(path);  // throws io::ParseError with file and line
        if (mesh.triangles.empty()) throw io::ParseError(path, 0, "the mesh has no triangles");
        return mesh;
    }
    bool s = false;
    TriangleMesh mesh = scenes::paperModel(dataDir.empty() ? scenes::defaultDataDir() : dataDir, model, &s);
    standIn = standIn || s;
    return mesh;
}

}  // namespace

/// A rigid body with a GImpact mesh; the mesh is stored in the body's frame (origin at the centre of mass,
/// principal axes) in double for the culler-side views and in btScalar for Bullet.
struct Body {
    std::string name;
    TriangleMesh local;
    std::vector<btScalar> vertexData;
    std::vector<int> indexData;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btGImpactMeshShape> shape;
    std::unique_ptr<btDefaultMotionState> motion;
    std::unique_ptr<btRigidBody> body;
    bool breakable = false;
};

struct BreakableScene::Impl {
    BreakableOptions options;
    bool standIns = false;
    int fractureCount = 0;
    int frameIndex = 0;
    BreakableFrame frame;
    std::vector<std::pair<std::string, std::string>> stepPairs;
    std::vector<BreakableContact> stepContacts;

    std::unique_ptr<btDefaultCollisionConfiguration> config;
    std::unique_ptr<btBroadphaseInterface> broadphase;
    std::unique_ptr<btCollisionDispatcher> dispatcher;
    std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
    std::unique_ptr<btDiscreteDynamicsWorld> world;
    std::unique_ptr<btStaticPlaneShape> groundShape;
    std::unique_ptr<btCollisionObject> ground;
    std::vector<std::unique_ptr<Body>> bodies;
    double breakImpulse = 0.0;

    CullideBroadphase* cullideBp = nullptr;
    CullideCollisionDispatcher* cullideDisp = nullptr;
    TimedBroadphase<btDbvtBroadphase>* dbvt = nullptr;
    TimedBroadphase<btAxisSweep3>* sweep = nullptr;
    TimedDispatcher* timedDisp = nullptr;

    explicit Impl(const BreakableOptions& o) : options(o) {
        if (options.pieces < 1 || options.pieces > 256)
            throw std::invalid_argument("BreakableScene: pieces must be in 1..256");
        if (!std::isfinite(options.breakImpulse))
            throw std::invalid_argument("BreakableScene: breakImpulse must be finite");
        TriangleMesh falling = loadMesh(options.fallingMesh, options.dataDir, scenes::PaperModel::Bunny, standIns);
        TriangleMesh breakable = loadMesh(options.breakableMesh, options.dataDir, scenes::PaperModel::Dragon, standIns);
        normalize(falling, kFallingSize);
        normalize(breakable, kDragonSize);

        config = std::make_unique<btDefaultCollisionConfiguration>();
        switch (options.pipeline) {
        case CollisionPipeline::Cullide: {
            auto bp = std::make_unique<CullideBroadphase>(options.culler);
            bp->setDeepPenetrationFallback(options.deepPenetrationFallback);
            for (CulledKind kind : {CulledKind::GImpactPair, CulledKind::GImpactMesh, CulledKind::GImpactConvex,
                                    CulledKind::ConvexMesh})
                bp->setCulling(kind, options.culling);
            cullideBp = bp.get();
            broadphase = std::move(bp);
            auto d = std::make_unique<CullideCollisionDispatcher>(config.get(), cullideBp);
            d->setNarrowPhaseThreads(options.narrowPhaseThreads);
            cullideDisp = d.get();
            dispatcher = std::move(d);
            break;
        }
        case CollisionPipeline::BulletDbvt: {
            auto bp = std::make_unique<TimedBroadphase<btDbvtBroadphase>>();
            dbvt = bp.get();
            broadphase = std::move(bp);
            break;
        }
        case CollisionPipeline::BulletAxisSweep: {
            auto bp = std::make_unique<TimedBroadphase<btAxisSweep3>>(btVector3(-20, -5, -20), btVector3(20, 20, 20));
            sweep = bp.get();
            broadphase = std::move(bp);
            break;
        }
        }
        if (dispatcher == nullptr) {
            auto d = std::make_unique<TimedDispatcher>(config.get());
            timedDisp = d.get();
            dispatcher = std::move(d);
        }
        btGImpactCollisionAlgorithm::registerAlgorithm(dispatcher.get());
        solver = std::make_unique<btSequentialImpulseConstraintSolver>();
        world = std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), broadphase.get(), solver.get(),
                                                          config.get());
        world->setGravity(btVector3(0, btScalar(-9.81), 0));

        groundShape = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), btScalar(0));
        ground = std::make_unique<btCollisionObject>();
        ground->setCollisionShape(groundShape.get());
        ground->setFriction(btScalar(0.8));
        world->addCollisionObject(ground.get(), btBroadphaseProxy::StaticFilter,
                                  btBroadphaseProxy::AllFilter ^ btBroadphaseProxy::StaticFilter);

        // The breakable object stands on the ground, static until it breaks; the falling one starts above it,
        // slightly off-centre and tilted, moving down.
        const Aabb bb = scenes::boundsOf(breakable);
        Body& dragon = addBody("dragon", breakable, Vec3(0, -bb.min.y(), 0), 0.0);
        dragon.breakable = true;
        const double top = bb.max.y() - bb.min.y();
        const Eigen::Affine3d tilt(Eigen::AngleAxisd(0.3, Vec3(1, 0, 1).normalized()));
        scenes::transformMesh(falling, tilt);
        const Aabb tb = scenes::boundsOf(falling);
        Body& bunny = addBody("bunny", falling, Vec3(0.1 * kDragonSize, top - tb.min.y() + 0.6, 0.05), kDensity);
        bunny.body->setLinearVelocity(btVector3(0, btScalar(-3.0), 0));
        // Breaks on a hard impact, not under resting contact (m g dt is ~0.2 m N s per step).
        breakImpulse = options.breakImpulse >= 0 ? options.breakImpulse : 1.5 * double(bunny.body->getMass());
    }

    /// Declared after everything the world refers to, so it runs first, also when the constructor throws.
    struct WorldCleanup {
        Impl& impl;
        ~WorldCleanup() {
            if (!impl.world) return;
            for (auto& b : impl.bodies) impl.world->removeRigidBody(b->body.get());
            if (impl.ground) impl.world->removeCollisionObject(impl.ground.get());
        }
    } cleanup{*this};

    /// Adds a body whose triangles are `mesh` in world space, placed at `offset`. mass density 0: static.
    Body& addBody(const std::string& name, const TriangleMesh& mesh, const Vec3& offset, double density) {
        auto b = std::make_unique<Body>();
        b->name = name;
        const MassProperties mp = hullMassProperties(referencedVertices(mesh), density > 0 ? density : 1.0,
                                                     1e-3 * kDragonSize);
        // Body frame: centre of mass + principal axes; the mesh is stored in it.
        const Eigen::Matrix3d R = mp.axes;
        b->local.triangles = mesh.triangles;
        b->local.vertices.reserve(mesh.vertices.size());
        for (const Vec3& v : mesh.vertices) b->local.vertices.push_back(R.transpose() * (v - mp.centre));
        for (const Vec3& v : b->local.vertices)
            b->vertexData.insert(b->vertexData.end(), {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())});
        for (const TriangleIndices& t : b->local.triangles)
            b->indexData.insert(b->indexData.end(), {int(t[0]), int(t[1]), int(t[2])});
        b->array = std::make_unique<btTriangleIndexVertexArray>(
            int(b->local.triangles.size()), b->indexData.data(), int(3 * sizeof(int)),
            int(b->local.vertices.size()), b->vertexData.data(), int(3 * sizeof(btScalar)));
        b->shape = std::make_unique<btGImpactMeshShape>(b->array.get());
        b->shape->setMargin(kMargin);
        b->shape->updateBound();

        btMatrix3x3 basis;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) basis[r][c] = btScalar(R(r, c));
        const Vec3 origin = mp.centre + offset;
        btTransform start(basis, btVector3(btScalar(origin.x()), btScalar(origin.y()), btScalar(origin.z())));
        b->motion = std::make_unique<btDefaultMotionState>(start);
        const btScalar mass = density > 0 ? btScalar(mp.mass) : btScalar(0);
        const btVector3 inertia = density > 0 ? btVector3(btScalar(mp.inertia.x()), btScalar(mp.inertia.y()),
                                                          btScalar(mp.inertia.z()))
                                              : btVector3(0, 0, 0);
        btRigidBody::btRigidBodyConstructionInfo info(mass, b->motion.get(), b->shape.get(), inertia);
        info.m_friction = btScalar(0.6);
        info.m_restitution = btScalar(0.1);
        b->body = std::make_unique<btRigidBody>(info);
        b->body->setUserPointer(b.get());
        if (density > 0) b->body->setCcdMotionThreshold(0);  // discrete, like the regression scenes
        bodies.push_back(std::move(b));  // owned first: the world never holds a body nobody owns
        world->addRigidBody(bodies.back()->body.get());
        return *bodies.back();
    }

    TriangleMesh worldMesh(const Body& b) const {
        const btTransform& t = b.body->getWorldTransform();
        Eigen::Matrix3d R;
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) R(r, c) = double(t.getBasis()[r][c]);
        const Vec3 o(double(t.getOrigin().x()), double(t.getOrigin().y()), double(t.getOrigin().z()));
        TriangleMesh m;
        m.triangles = b.local.triangles;
        m.vertices.reserve(b.local.vertices.size());
        for (const Vec3& v : b.local.vertices) m.vertices.push_back(R * v + o);
        return m;
    }

    /// Sums the contact impulses on each breakable body; breaks the ones over the threshold at the
    /// impulse-weighted contact point. Returns the number of pieces created.
    std::size_t fractureWhatBroke() {
        std::map<Body*, std::pair<double, Vec3>> load;  // impulse, impulse-weighted point
        const int manifolds = dispatcher->getNumManifolds();
        for (int i = 0; i < manifolds; ++i) {
            btPersistentManifold* m = dispatcher->getManifoldByIndexInternal(i);
            const auto* o0 = static_cast<const btCollisionObject*>(m->getBody0());
            const auto* o1 = static_cast<const btCollisionObject*>(m->getBody1());
            for (const btCollisionObject* o : {o0, o1}) {
                auto* b = static_cast<Body*>(o->getUserPointer());
                if (b == nullptr || !b->breakable) continue;
                for (int c = 0; c < m->getNumContacts(); ++c) {
                    const btManifoldPoint& p = m->getContactPoint(c);
                    const double impulse = double(p.getAppliedImpulse());
                    if (!(impulse > 0)) continue;
                    const btVector3& w = o == o0 ? p.getPositionWorldOnA() : p.getPositionWorldOnB();
                    // Not load[b]: a default-constructed Eigen vector is uninitialised.
                    auto& entry = load.try_emplace(b, 0.0, Vec3::Zero()).first->second;
                    entry.first += impulse;
                    entry.second += impulse * Vec3(double(w.x()), double(w.y()), double(w.z()));
                }
            }
        }
        std::size_t created = 0;
        // Deterministic order: by position in `bodies`.
        std::vector<Body*> broken;
        for (auto& b : bodies)
            if (load.count(b.get()) && load[b.get()].first > breakImpulse) broken.push_back(b.get());
        for (Body* b : broken) {
            const Vec3 impact = load[b].second / load[b].first;
            created += breakBody(*b, impact);
        }
        return created;
    }

    std::size_t breakBody(Body& b, const Vec3& impact) {
        const TriangleMesh mesh = worldMesh(b);
        const Aabb box = scenes::boundsOf(mesh);
        const std::uint64_t seed = options.seed * 0x9E3779B97F4A7C15ull + std::uint64_t(fractureCount) + 1;
        const auto sites = fractureSites(box, impact, options.pieces, seed);
        const auto pieces = voronoiCut(mesh, sites, kGapFraction * box.extent().maxCoeff());
        const btVector3 v = b.body->getLinearVelocity();
        const btVector3 w = b.body->getAngularVelocity();
        const std::string base = b.name;
        removeBody(b);
        std::size_t created = 0;
        for (std::size_t i = 0; i < pieces.size(); ++i) {
            if (pieces[i].triangles.empty()) continue;
            Body& piece = addBody(base + "." + std::to_string(i), pieces[i], Vec3::Zero(), kDensity);
            piece.body->setLinearVelocity(v);
            piece.body->setAngularVelocity(w);
            ++created;
        }
        ++fractureCount;
        return created;
    }

    void removeBody(Body& b) {
        world->removeRigidBody(b.body.get());
        bodies.erase(std::find_if(bodies.begin(), bodies.end(), [&](const auto& p) { return p.get() == &b; }));
    }

    static const std::string& nameOf(const btCollisionObject* o) {
        static const std::string ground = "ground";
        const auto* b = static_cast<const Body*>(o->getUserPointer());
        return b ? b->name : ground;
    }

    /// The manifolds' points as BreakableContacts (bodies by name, first < second), sorted.
    void recordContacts() {
        stepContacts.clear();
        for (int i = 0; i < dispatcher->getNumManifolds(); ++i) {
            const btPersistentManifold* m = dispatcher->getManifoldByIndexInternal(i);
            const std::string& n0 = nameOf(m->getBody0());
            const std::string& n1 = nameOf(m->getBody1());
            const bool swap = n1 < n0;
            for (int c = 0; c < m->getNumContacts(); ++c) {
                const btManifoldPoint& p = m->getContactPoint(c);
                BreakableContact k;
                k.body0 = swap ? n1 : n0;
                k.body1 = swap ? n0 : n1;
                k.part0 = swap ? p.m_partId1 : p.m_partId0;
                k.index0 = swap ? p.m_index1 : p.m_index0;
                k.part1 = swap ? p.m_partId0 : p.m_partId1;
                k.index1 = swap ? p.m_index0 : p.m_index1;
                k.distance = double(p.getDistance());
                stepContacts.push_back(std::move(k));
            }
        }
        std::sort(stepContacts.begin(), stepContacts.end(), [](const BreakableContact& a, const BreakableContact& b) {
            return std::tie(a.body0, a.body1, a.part0, a.index0, a.part1, a.index1, a.distance) <
                   std::tie(b.body0, b.body1, b.part0, b.index0, b.part1, b.index1, b.distance);
        });
    }

    const BreakableFrame& step() {
        double bp0 = 0, np0 = 0;
        if (dbvt) bp0 = dbvt->ms;
        if (sweep) bp0 = sweep->ms;
        if (timedDisp) np0 = timedDisp->ms;
        Timer total;
        world->stepSimulation(btScalar(kDt), 1, btScalar(kDt));
        const double stepMs = total.ms();
        BreakableFrame f;
        f.frame = frameIndex++;
        if (cullideBp) {
            f.cullide = cullideBp->getLastFrameStats();
            f.broadphaseMs = f.cullide.totalMs;
            f.narrowphaseMs = cullideDisp->getLastStepStats().dispatchMs;
            f.trianglePairs = cullideDisp->getLastStepStats().trianglePairs;
        } else {
            f.broadphaseMs = (dbvt ? dbvt->ms : sweep->ms) - bp0;
            f.narrowphaseMs = timedDisp->ms - np0;
        }
        f.solverMs = std::max(0.0, stepMs - f.broadphaseMs - f.narrowphaseMs);
        btOverlappingPairCache* cache = broadphase->getOverlappingPairCache();
        f.broadphasePairs = std::size_t(cache->getNumOverlappingPairs());
        stepPairs.clear();
        for (int i = 0; i < cache->getNumOverlappingPairs(); ++i) {
            const btBroadphasePair& p = cache->getOverlappingPairArray()[i];
            const auto* b0 = static_cast<const Body*>(
                static_cast<const btCollisionObject*>(p.m_pProxy0->m_clientObject)->getUserPointer());
            const auto* b1 = static_cast<const Body*>(
                static_cast<const btCollisionObject*>(p.m_pProxy1->m_clientObject)->getUserPointer());
            if (b0 == nullptr || b1 == nullptr) continue;  // the ground plane
            stepPairs.emplace_back(std::min(b0->name, b1->name), std::max(b0->name, b1->name));
        }
        std::sort(stepPairs.begin(), stepPairs.end());
        for (int i = 0; i < dispatcher->getNumManifolds(); ++i)
            f.contacts += std::size_t(dispatcher->getManifoldByIndexInternal(i)->getNumContacts());
        double recordMs = 0;  // the comparison's, not the frame's: left out of totalMs
        if (options.recordContacts) {
            const Timer record;
            recordContacts();
            recordMs = record.ms();
        }
        Timer fracture;
        f.brokenPieces = fractureWhatBroke();
        f.fractureMs = fracture.ms();
        f.totalMs = total.ms() - recordMs;
        f.bodies = bodies.size();
        for (const auto& b : bodies) f.triangles += b->local.triangles.size();
        frame = f;
        return frame;
    }
};

BreakableScene::BreakableScene(const BreakableOptions& options) : m_impl(std::make_unique<Impl>(options)) {}
BreakableScene::~BreakableScene() = default;

const BreakableFrame& BreakableScene::step() { return m_impl->step(); }
const BreakableFrame& BreakableScene::lastFrame() const { return m_impl->frame; }

std::vector<TriangleMesh> BreakableScene::worldMeshes() const {
    std::vector<TriangleMesh> out;
    out.reserve(m_impl->bodies.size());
    for (const auto& b : m_impl->bodies) out.push_back(m_impl->worldMesh(*b));
    return out;
}

std::vector<std::string> BreakableScene::bodyNames() const {
    std::vector<std::string> out;
    for (const auto& b : m_impl->bodies) out.push_back(b->name);
    return out;
}

const std::vector<std::pair<std::string, std::string>>& BreakableScene::lastStepPairs() const {
    return m_impl->stepPairs;
}
const std::vector<BreakableContact>& BreakableScene::lastStepContacts() const { return m_impl->stepContacts; }
int BreakableScene::fractures() const { return m_impl->fractureCount; }
bool BreakableScene::usedStandIns() const { return m_impl->standIns; }
const CullideBroadphase* BreakableScene::cullideBroadphase() const { return m_impl->cullideBp; }
const CullideCollisionDispatcher* BreakableScene::cullideDispatcher() const { return m_impl->cullideDisp; }

}  // namespace cullide::demo
