// FCL (libfcl-dev 0.7) as a benchmark engine: one fcl::BVHModel<OBBRSSd> (or <AABBd>) per object (deforming meshes refitted with
// beginUpdateModel / updateSubModel / endUpdateModel, rigid ones moved by their transform), a
// DynamicAABBTreeCollisionManager broadphase and fcl::collide per candidate object pair with a contact limit large
// enough to enumerate every intersecting triangle pair (Contact::b1 / b2 are the triangle ids).
#pragma once

#include "Engine.h"

#include <memory>

namespace cullide::bench {

class FclEngine final : public Engine {
public:
    /// Bounding volume of the BVH: OBBRSS (FCL's usual choice for meshes) or AABB (cheaper to refit).
    enum class Volume { Obbrss, Aabb };

    explicit FclEngine(Volume volume);
    ~FclEngine() override;

    void setup(const BenchFrame& first) override;
    void run(const BenchFrame& frame, FrameOutput& out) override;
    nlohmann::json describe() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::bench
