// Bullet's own collision pipeline as a benchmark engine: a btCollisionWorld with one btGImpactMeshShape per object
// (deforming meshes: vertex arrays rewritten in place, postUpdate() + updateBound() refit; rigid ones: a transform),
// btDbvtBroadphase or btAxisSweep3, btCollisionDispatcher with GImpact registered. The triangle pairs reported are
// those GImpact produced contact points for (recorded by gContactAddedCallback).
#pragma once

#include "Engine.h"

#include <memory>

namespace cullide::bench {

class BulletEngine final : public Engine {
public:
    enum class Broadphase { Dbvt, AxisSweep };

    explicit BulletEngine(Broadphase broadphase);
    ~BulletEngine() override;

    void setup(const BenchFrame& first) override;
    void run(const BenchFrame& frame, FrameOutput& out) override;
    nlohmann::json describe() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::bench
