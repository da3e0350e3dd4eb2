// What cullide-demo runs frame by frame: the breakable Bullet scene or one of the paper's environments through the
// culler. Every runner gives the frame's meshes and a culling result for them (for snapshots and checks).
#pragma once

#include "FrameLog.h"

#include "cullide/Culler.h"
#include "cullide/Settings.h"
#include "cullide/Types.h"
#include "cullide_bullet/CullideBroadphase.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cullide::demo {

struct RunnerOptions {
    std::string scene = "breakable";  ///< breakable | env1 | env2 | env3
    std::uint64_t seed = 1;
    Settings culler;
    std::string mesh;                 ///< --mesh: the falling object (breakable)
    std::string breakableMesh;        ///< --breakable-mesh
    int objects = 0;                  ///< env1/env2 object count (0 = the paper's)
    std::string pipeline = "cullide"; ///< breakable: cullide | bullet-dbvt | bullet-axis-sweep
    bool deepPenetrationFallback = true; ///< breakable, cullide: --deep-penetration-fallback on|off
    Culling culling = Culling::Auto;     ///< breakable, cullide: --culling auto|on|off
};

class SceneRunner {
public:
    virtual ~SceneRunner() = default;
    /// Runs the next frame. With `check`, the frame is also compared with the exact brute-force reference and
    /// FrameRecord::missed is set.
    virtual FrameRecord advance(bool check) = 0;
    /// World-space meshes of the current state and their names.
    virtual const std::vector<TriangleMesh>& meshes() = 0;
    virtual std::vector<std::string> names() const = 0;
    /// A culling result for meshes() (pcsTriangles and pairs), computed on demand where the frame did not
    /// produce one directly.
    virtual const Result& cullResult() = 0;
    /// Ground geometry to draw (none for the environments).
    virtual std::optional<TriangleMesh> ground() const { return std::nullopt; }
    virtual std::string renderer() const = 0;
    virtual std::string device() const = 0;
    virtual bool usedStandIns() const = 0;
    virtual int fractures() const { return 0; }
    /// Breakable, cullide: what Culling::Auto decided for the pieces' pairs (GImpact-GImpact); else nothing.
    virtual std::optional<CullingDecision> cullingDecision() const { return std::nullopt; }
    virtual int defaultFrames() const = 0;
};

/// Throws std::invalid_argument for an unknown scene, io::ParseError / std::runtime_error for unreadable meshes,
/// GlUnavailableError without GL.
std::unique_ptr<SceneRunner> makeSceneRunner(const RunnerOptions& options);

}  // namespace cullide::demo
