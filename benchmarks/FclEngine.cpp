#include "FclEngine.h"

#include "cullide/Timer.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include <cstdint>
#include <vector>

namespace cullide::bench {

namespace {

struct CollideData {
    fcl::CollisionRequestd request;
    std::vector<TriangleKey>* sink = nullptr;
};

std::uint32_t indexOf(const fcl::CollisionObjectd* o) {
    return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(o->getUserData()));
}

bool collideCallback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
    auto* d = static_cast<CollideData*>(data);
    fcl::CollisionResultd result;
    fcl::collide(o1, o2, d->request, result);
    const std::uint32_t a = indexOf(o1), b = indexOf(o2);
    for (std::size_t k = 0; k < result.numContacts(); ++k) {
        const fcl::Contactd& c = result.getContact(k);
        // b1 is a triangle of the first object handed to collide() (Contact::o1 may point to a transformed copy
        // of its geometry, as for AABB models).
        d->sink->push_back({a, static_cast<std::uint32_t>(c.b1), b, static_cast<std::uint32_t>(c.b2)});
    }
    return false;  // never stop early
}

/// The per-object models for one bounding-volume type.
class Models {
public:
    virtual ~Models() = default;
    virtual std::shared_ptr<fcl::CollisionGeometryd> build(const TriangleMesh& mesh) = 0;
    /// Refit object i's BVH to new vertices (same triangles) and its local box.
    virtual void refit(std::size_t i, const std::vector<Vec3>& vertices) = 0;
};

template <class BV>
class ModelsOf final : public Models {
public:
    std::shared_ptr<fcl::CollisionGeometryd> build(const TriangleMesh& mesh) override {
        std::vector<fcl::Triangle> triangles;
        triangles.reserve(mesh.triangles.size());
        for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
        auto model = std::make_shared<fcl::BVHModel<BV>>();
        model->beginModel(static_cast<int>(mesh.triangles.size()), static_cast<int>(mesh.vertices.size()));
        model->addSubModel(mesh.vertices, triangles);
        model->endModel();
        model->computeLocalAABB();
        m_models.push_back(model);
        return model;
    }
    void refit(std::size_t i, const std::vector<Vec3>& vertices) override {
        fcl::BVHModel<BV>& model = *m_models[i];
        model.beginUpdateModel();
        model.updateSubModel(vertices);
        model.endUpdateModel(true, true);
        // The object's broadphase box comes from the geometry's local box, which the refit does not update.
        model.computeLocalAABB();
    }

private:
    std::vector<std::shared_ptr<fcl::BVHModel<BV>>> m_models;
};

}  // namespace

struct FclEngine::Impl {
    Volume volume = Volume::Obbrss;
    std::unique_ptr<Models> models;
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
    std::vector<Motion> motion;
    fcl::DynamicAABBTreeCollisionManagerd manager;
    std::vector<TriangleKey> contacts;
};

FclEngine::FclEngine(Volume volume) : m_impl(std::make_unique<Impl>()) {
    m_impl->volume = volume;
    if (volume == Volume::Obbrss)
        m_impl->models = std::make_unique<ModelsOf<fcl::OBBRSSd>>();
    else
        m_impl->models = std::make_unique<ModelsOf<fcl::AABBd>>();
}

FclEngine::~FclEngine() = default;

void FclEngine::setup(const BenchFrame& first) {
    Impl& m = *m_impl;
    std::vector<fcl::CollisionObjectd*> raw;
    for (std::size_t i = 0; i < first.local->size(); ++i) {
        const Motion motion = (*first.motion)[i];
        const TriangleMesh& mesh = motion == Motion::Deforming ? (*first.world)[i] : (*first.local)[i];
        const fcl::Transform3d pose = motion == Motion::Deforming ? fcl::Transform3d::Identity() : first.poses[i];
        auto object = std::make_unique<fcl::CollisionObjectd>(m.models->build(mesh), pose);
        object->setUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(i)));
        raw.push_back(object.get());
        m.objects.push_back(std::move(object));
        m.motion.push_back(motion);
    }
    m.manager.registerObjects(raw);
    m.manager.setup();
}

void FclEngine::run(const BenchFrame& frame, FrameOutput& out) {
    Impl& m = *m_impl;
    out.clear();
    m.contacts.clear();
    const Timer total;
    Timer stage;
    for (std::size_t i = 0; i < m.objects.size(); ++i) {
        if (m.motion[i] == Motion::Deforming) {
            m.models->refit(i, (*frame.world)[i].vertices);
            m.objects[i]->computeAABB();
        } else if (m.motion[i] == Motion::Rigid) {
            m.objects[i]->setTransform(frame.poses[i]);
            m.objects[i]->computeAABB();
        }
    }
    out.stages.push_back({"refit", stage.ms()});
    stage = Timer();
    m.manager.update();
    out.stages.push_back({"broadphase", stage.ms()});
    stage = Timer();
    CollideData data;
    data.request.num_max_contacts = std::size_t(1) << 40;
    data.request.enable_contact = false;
    data.sink = &m.contacts;
    m.manager.collide(&data, collideCallback);
    out.stages.push_back({"narrow phase", stage.ms()});
    out.totalMs = total.ms();
    for (const TriangleKey& c : m.contacts) out.pairs.addTriangle(c[0], c[1], c[2], c[3]);
    out.pairs.finish();
}

nlohmann::json FclEngine::describe() const {
    nlohmann::json j;
    j["mode"] = m_impl->volume == Volume::Obbrss ? "bvh-obbrss" : "bvh-aabb";
    j["version"] = FCL_VERSION;
    j["threads"] = 1;
    return j;
}

}  // namespace cullide::bench
