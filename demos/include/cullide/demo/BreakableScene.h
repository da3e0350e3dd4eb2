// The breakable-object scene (the paper's Fig. 6): the Stanford bunny falls through the Chinese dragon, which breaks
// into pieces on impact. Bullet rigid-body dynamics; the collision pipeline is CULLIDE's (CullideBroadphase +
// CullideCollisionDispatcher, the two-line swap) or Bullet's own, for comparisons. Deterministic for a seed.
// Shared by the demo, the benchmarks and the tests.
#pragma once

#include "cullide/Settings.h"
#include "cullide/Types.h"
#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cullide::demo {

enum class CollisionPipeline {
    Cullide,          ///< CullideBroadphase + CullideCollisionDispatcher
    BulletDbvt,       ///< btDbvtBroadphase + btCollisionDispatcher (+ GImpact)
    BulletAxisSweep,  ///< btAxisSweep3 + btCollisionDispatcher (+ GImpact)
};

struct BreakableOptions {
    std::string dataDir;        ///< where bunny00.off / ChineseDragon-10kv.off live ("" = scenes::defaultDataDir())
    std::string fallingMesh;    ///< OFF/OBJ of the falling object ("" = the bunny)
    std::string breakableMesh;  ///< OFF/OBJ of the breakable object ("" = the dragon)
    std::uint64_t seed = 1;
    int pieces = 12;            ///< Voronoi cells the breakable object is cut into
    double breakImpulse = -1;   ///< total contact impulse (N s) that breaks it; < 0: scaled to the falling mass
    CollisionPipeline pipeline = CollisionPipeline::Cullide;
    Settings culler;            ///< CULLIDE settings (pipeline Cullide)
    /// CullideBroadphase::setDeepPenetrationFallback (pipeline Cullide, culled GImpact pairs): intersecting GImpact
    /// pairs get Bullet's contacts; off: interpenetrating pieces see fewer contacts.
    bool deepPenetrationFallback = true;
    /// Cullide pipeline: every culling switch of the broadphase (Culling::Auto, the default: culled where a trial
    /// shows it pays on a machine with a hardware GL device; Off: the pieces get Bullet's GImpact contacts bit for
    /// bit; On: the pieces' pairs go through the culler).
    Culling culling = Culling::Auto;
    /// Cullide pipeline: CullideCollisionDispatcher::setNarrowPhaseThreads (0: the dispatcher's default).
    unsigned narrowPhaseThreads = 0;
    /// Keep every step's contact points (lastStepContacts), for comparing pipelines; off: not collected.
    bool recordContacts = false;
};

/// A contact point after a step's collision detection: the bodies by name ("ground" for the plane), first < second,
/// and the point's triangle keys (part, triangle) on each side in that order, as the narrow phase set them.
struct BreakableContact {
    std::string body0, body1;
    int part0 = 0, index0 = 0, part1 = 0, index1 = 0;
    double distance = 0.0;
};

/// What one step did.
struct BreakableFrame {
    int frame = 0;
    std::size_t bodies = 0;          ///< rigid bodies with triangle geometry (excl. the ground plane)
    std::size_t triangles = 0;       ///< their triangles
    std::size_t brokenPieces = 0;    ///< pieces created by fractures this step
    std::size_t broadphasePairs = 0; ///< pairs in the overlapping pair cache after the broadphase
    std::size_t trianglePairs = 0;   ///< triangle pairs handed to the narrow phase (CULLIDE) / 0 when unknown
    std::size_t contacts = 0;        ///< contact points in all manifolds after the step
    double broadphaseMs = 0, narrowphaseMs = 0, solverMs = 0, fractureMs = 0, totalMs = 0;
    CullideFrameStats cullide;       ///< CULLIDE broadphase statistics (pipeline Cullide)
};

class BreakableScene {
public:
    /// Throws std::runtime_error for unreadable meshes, GlUnavailableError without GL (pipeline Cullide).
    explicit BreakableScene(const BreakableOptions& options);
    ~BreakableScene();
    BreakableScene(const BreakableScene&) = delete;
    BreakableScene& operator=(const BreakableScene&) = delete;

    /// Advances the simulation by one frame (1/60 s) and fractures what broke.
    const BreakableFrame& step();
    const BreakableFrame& lastFrame() const;

    /// World-space triangle meshes of the bodies (the ground plane excluded), in a stable order.
    std::vector<TriangleMesh> worldMeshes() const;
    /// Names of the bodies in the same order ("bunny", "dragon", "dragon.3", ...).
    std::vector<std::string> bodyNames() const;
    /// Body pairs (names, first < second) in Bullet's overlapping pair cache right after the last step's collision
    /// detection (before that step's fractures); pairs with the ground plane are left out. Sorted.
    const std::vector<std::pair<std::string, std::string>>& lastStepPairs() const;
    /// Every contact point in the manifolds right after the last step's collision detection and solve (before that
    /// step's fractures), sorted; empty unless BreakableOptions::recordContacts.
    const std::vector<BreakableContact>& lastStepContacts() const;
    int fractures() const;
    /// True when a real mesh was missing and a procedural stand-in was used.
    bool usedStandIns() const;
    /// The CULLIDE broadphase (pipeline Cullide), else nullptr.
    const CullideBroadphase* cullideBroadphase() const;
    /// The CULLIDE dispatcher (pipeline Cullide), else nullptr.
    const CullideCollisionDispatcher* cullideDispatcher() const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace cullide::demo
