// A frame source for the side-by-side runs: one of the shared environments (scenes/) with, per object, how it moves
// (static, rigid, deforming). Every engine sees the same world-space meshes; engines that model rigid motion as a
// transform (Bullet, FCL) get each rigid object's frame-0 mesh and its pose, recovered from the world vertices.
#pragma once

#include "cullide/Types.h"
#include "cullide/scenes/Environments.h"

#include <Eigen/Geometry>

#include <memory>
#include <string>
#include <vector>

namespace cullide::bench {

enum class Motion { Static, Rigid, Deforming };

/// One frame as the engines see it.
struct BenchFrame {
    int index = 0;
    const std::vector<TriangleMesh>* world = nullptr;  ///< world-space meshes of this frame
    const std::vector<TriangleMesh>* local = nullptr;  ///< frame-0 meshes: local geometry of static/rigid objects
    const std::vector<Motion>* motion = nullptr;
    /// world = pose * local for static and rigid objects (identity for deforming ones).
    std::vector<Eigen::Isometry3d> poses;
};

struct SceneParams {
    std::string name;            ///< env1 | env2 | env3 | env3-deform
    int objects = -1;            ///< env1/env2: object count (-1: the environment's default)
    int trianglesPerObject = -1; ///< env1/env2: triangles per object (-1: default)
    std::uint64_t seed = 1;
};

class BenchScene {
public:
    /// Throws std::invalid_argument for an unknown scene name.
    explicit BenchScene(const SceneParams& params);

    /// Frame `f` (any order). The returned frame refers to storage inside the scene, valid until the next call.
    BenchFrame frame(int f);

    const SceneParams& params() const { return m_params; }
    bool usedStandIns() const { return m_standIns; }
    std::size_t objectCount() const { return m_local.size(); }
    std::size_t triangleCount() const;
    const std::vector<Motion>& motion() const { return m_motion; }

private:
    SceneParams m_params;
    std::unique_ptr<scenes::Environment> m_env;
    std::vector<TriangleMesh> m_local;
    std::vector<Motion> m_motion;
    bool m_standIns = false;
};

}  // namespace cullide::bench
