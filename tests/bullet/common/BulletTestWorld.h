// Test harness for the Bullet adapter: the same scene built in a world with Bullet's default pipeline
// (btDbvtBroadphase + btCollisionDispatcher) and in one with CULLIDE (CullideBroadphase +
// CullideCollisionDispatcher), per-step timing of both, and contact comparison between them.
#pragma once

#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <btBulletDynamicsCommon.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace cullide::test {

enum class PipelineKind { Default, Cullide };

/// Shapes shared by the mirrored worlds (identical geometry), with the arrays their meshes reference.
class ShapeStore {
public:
    ShapeStore();
    ~ShapeStore();
    ShapeStore(const ShapeStore&) = delete;
    ShapeStore& operator=(const ShapeStore&) = delete;

    btCollisionShape* box(const btVector3& halfExtents);
    btCollisionShape* sphere(btScalar radius);
    btCollisionShape* capsule(btScalar radius, btScalar height);
    /// An irregular convex hull (btConvexHullShape) of `points` points on an ellipsoid with the given radii.
    btCollisionShape* hull(const btVector3& radii, int points, std::uint32_t seed);
    /// A closed convex mesh (a UV ellipsoid of `rings` x `segments` quads, split in triangles, with the given radii)
    /// as a btConvexTriangleMeshShape over a btTriangleIndexVertexArray, or over a btStridingMeshInterface of the
    /// application's own class (`ownInterface`).
    btCollisionShape* convexMesh(const btVector3& radii, int rings, int segments, bool ownInterface = false);
    /// Static landscape: cells x cells grid of `cellSize`, rolling hills, as a btBvhTriangleMeshShape.
    btCollisionShape* landscape(int cells, btScalar cellSize, btScalar amplitude);
    /// btGImpactMeshShape torus (updateBound() called), major radius R, minor r, its vertices around `centre`.
    btCollisionShape* gimpactTorus(btScalar R, btScalar r, int segments, int sides, btScalar margin,
                                   const btVector3& centre = btVector3(0, 0, 0));
    btCollisionShape* plane(const btVector3& normal, btScalar constant);

private:
    struct Mesh;
    std::vector<std::unique_ptr<Mesh>> m_meshes;
    std::vector<std::unique_ptr<btCollisionShape>> m_shapes;
};

/// A dynamics world with either pipeline. Objects get user index = their creation order, so mirrored worlds can
/// be compared object by object.
class TestWorld {
public:
    /// With PipelineKind::Cullide, `factory` creates the culler (default: the GPU culler).
    explicit TestWorld(PipelineKind kind, CullideBroadphase::CullerFactory factory = {},
                       const Settings& settings = Settings{});
    ~TestWorld();
    TestWorld(const TestWorld&) = delete;
    TestWorld& operator=(const TestWorld&) = delete;

    btDiscreteDynamicsWorld& world() { return *m_world; }
    btCollisionDispatcher& dispatcher() { return *m_dispatcher; }
    btBroadphaseInterface& broadphase() { return *m_broadphase; }
    CullideBroadphase* cullideBroadphase() { return m_cullideBroadphase; }
    CullideCollisionDispatcher* cullideDispatcher() { return m_cullideDispatcher; }
    PipelineKind kind() const { return m_kind; }

    btRigidBody* addBody(btCollisionShape* shape, btScalar mass, const btTransform& transform, int group = 0,
                         int mask = 0);
    void removeBody(btRigidBody* body);
    btCollisionObject* objectByIndex(int index) const;
    const std::vector<btCollisionObject*>& objects() const { return m_objectsByIndex; }
    int nextIndex() const { return static_cast<int>(m_objectsByIndex.size()); }
    /// Takes ownership of an object added by the caller (ghosts etc.), assigning the next index.
    void adopt(std::unique_ptr<btCollisionObject> object);

    void step(btScalar dt = btScalar(1.0 / 60.0));
    /// Collision detection of a step without the solver: unconstrained motion, CCD's predictive contacts,
    /// updateAabbs, pairs, narrow phase (timed).
    void detectCollisions(btScalar dt = btScalar(1.0 / 60.0));

    /// Timing of the last collision detection: broadphase (calculateOverlappingPairs) and narrow phase
    /// (dispatchAllCollisionPairs), and the pair count handed to the narrow phase.
    double lastBroadphaseMs() const;
    double lastNarrowPhaseMs() const;
    std::size_t lastPairCount() const;

    /// Per-step hook run inside solveConstraints (mid-step), after the solver.
    std::function<void(TestWorld&)> midStep;

private:
    class World;
    PipelineKind m_kind;
    std::unique_ptr<btDefaultCollisionConfiguration> m_config;
    std::unique_ptr<btBroadphaseInterface> m_broadphase;
    std::unique_ptr<btCollisionDispatcher> m_dispatcher;
    std::unique_ptr<btSequentialImpulseConstraintSolver> m_solver;
    std::unique_ptr<btDiscreteDynamicsWorld> m_world;
    CullideBroadphase* m_cullideBroadphase = nullptr;
    CullideCollisionDispatcher* m_cullideDispatcher = nullptr;
    std::vector<std::unique_ptr<btCollisionObject>> m_owned;
    std::vector<btCollisionObject*> m_objectsByIndex;
};

/// A btCollisionWorld (Bullet as a collision library) with either pipeline (the CULLIDE one with the CPU reference
/// culler); objects are plain btCollisionObjects (static-flagged, as Bullet makes them), and objects added in the
/// same order get the same user index. Bullet's GImpact algorithm is registered.
class CollisionOnlyWorld {
public:
    explicit CollisionOnlyWorld(PipelineKind kind);
    ~CollisionOnlyWorld();
    CollisionOnlyWorld(const CollisionOnlyWorld&) = delete;
    CollisionOnlyWorld& operator=(const CollisionOnlyWorld&) = delete;

    btCollisionObject* add(btCollisionShape* shape, const btTransform& t, int group = btBroadphaseProxy::DefaultFilter,
                           int mask = btBroadphaseProxy::AllFilter);
    btCollisionWorld& world() { return *m_world; }
    btCollisionDispatcher& dispatcher() { return *m_dispatcher; }
    btCollisionObject& object(std::size_t i) { return *m_objects[i]; }
    std::size_t size() const { return m_objects.size(); }

private:
    std::unique_ptr<btDefaultCollisionConfiguration> m_config;
    std::unique_ptr<btBroadphaseInterface> m_broadphase;
    std::unique_ptr<btCollisionDispatcher> m_dispatcher;
    std::unique_ptr<btCollisionWorld> m_world;
    std::vector<std::unique_ptr<btCollisionObject>> m_objects;
};

/// Contacts of one object pair (indices = user indices).
struct PairContacts {
    int points = 0;
    double minDistance = 1e30;
    std::vector<btVector3> positionsOnB;  ///< world positions (on the second object of the pair key)
    std::vector<btVector3> normalsOnB;    ///< contact normals on the second object of the pair key
    std::vector<double> distances;
};
using ContactMap = std::map<std::pair<int, int>, PairContacts>;

/// Every manifold point of the world (after a detection or step), keyed by (min index, max index).
ContactMap contactsOf(btCollisionWorld& world);

/// The pairs in the world's pair cache, as (min user index, max user index).
std::set<std::pair<int, int>> pairsOf(btCollisionWorld& world);

/// Makes `to` mirror `from`: transforms, velocities, activation state of every rigid body (by index).
void mirrorState(TestWorld& from, TestWorld& to);

struct ContactAgreement {
    std::size_t referencePairs = 0;   ///< pair-steps with contacts in the reference
    std::size_t missingPairs = 0;     ///< ... without any contact in the other world
    std::size_t comparedPairs = 0;
    std::size_t depthMismatches = 0;  ///< |min distance difference| > tolerance
    double maxDepthDifference = 0.0;
    std::size_t extraPairs = 0;       ///< pairs with contacts only in the other world
    /// Pairs compared point by point (tolerance at most kExactTolerance: Bullet's algorithm on identical input), and
    /// reference points without a twin (position, normal and distance) in the other world.
    std::size_t pointComparedPairs = 0;
    std::size_t pointMismatches = 0;
    static constexpr double kExactTolerance = 1e-5;
    std::string firstMissing;
    /// `tolerance(pair)` gives the allowed |min distance difference| of a pair.
    void add(const ContactMap& reference, const ContactMap& other,
             const std::function<double(const std::pair<int, int>&)>& tolerance);
};

/// Accumulated per-step measurements of one world.
struct StepTimes {
    double broadphaseMs = 0.0;
    double narrowMs = 0.0;
    std::size_t pairs = 0;
    std::size_t steps = 0;
    void add(const TestWorld& w) {
        broadphaseMs += w.lastBroadphaseMs();
        narrowMs += w.lastNarrowPhaseMs();
        pairs += w.lastPairCount();
        ++steps;
    }
    std::string summary(const char* name) const;
};

/// Creates a GPU culler factory or returns false (the caller then skips / fails per GlTestSupport's policy).
CullideBroadphase::CullerFactory gpuFactory();
CullideBroadphase::CullerFactory referenceFactory();

}  // namespace cullide::test
