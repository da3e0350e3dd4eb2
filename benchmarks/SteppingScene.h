// The Bullet adapter's regression scenes as a benchmark: a btDiscreteDynamicsWorld stepped at 60 Hz with
// CULLIDE (CullideBroadphase + CullideCollisionDispatcher) or Bullet's own pipeline (btDbvtBroadphase or
// btAxisSweep3 + btCollisionDispatcher). Scenes where CULLIDE has nothing to win, to show its overhead:
//   stack      a pyramid of 55 boxes on a static box
//   landscape  150 primitives and convex hulls dropped on a static 8,192-triangle landscape (btBvhTriangleMeshShape)
#pragma once

#include "Engine.h"

#include <memory>
#include <string>

namespace cullide::bench {

class SteppingScene {
public:
    /// scene: stack | landscape; engine: cullide | bullet-dbvt | bullet-sap. Throws std::invalid_argument.
    SteppingScene(const std::string& scene, const std::string& engine);
    ~SteppingScene();
    SteppingScene(const SteppingScene&) = delete;
    SteppingScene& operator=(const SteppingScene&) = delete;

    /// One stepSimulation(1/60): stages aabbs, broadphase, narrow phase, solver (integration, islands, rest).
    /// `out.pairs` holds the object pairs with contact points after the step.
    void step(FrameOutput& out);
    nlohmann::json describe() const;
    std::size_t objectCount() const;
    std::size_t triangleCount() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::bench
