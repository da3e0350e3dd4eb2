// What the broadphase hands to the culler each step: the objects of the pairs that go through it (meshes in their
// own frame with their transform, shared per shape, keyed so that the culler keeps their checks there; static ones
// world-space, kept between steps with the culler's static cache; box proxies for the rest), those pairs by object
// index, and what the margin rule needs of each.
#pragma once

#include "broadphase/CullingPolicy.h"
#include "broadphase/ShapeGeometry.h"
#include "cullide/Culler.h"
#include "cullide/Object.h"
#include "cullide/Result.h"
#include "cullide_bullet/CullideStats.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>
#include <LinearMath/btTransform.h>

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

namespace cullide::bullet {

/// What the broadphase keeps of an object that took part in a culled pair: its triangle geometry (shared per
/// shape), the transform that places it for the culler, and a world-space copy (static objects, kept between
/// steps with the culler's static cache; and pairs whose triangles the broadphase itself tests, built on demand).
struct CulledObject {
    std::uint64_t key = 0;  ///< staticKey of its world-space copy for the culler (never reused)
    /// staticKey of its shape's local mesh, handed over while it moves (never reused), and the version that goes
    /// with it: changed when the geometry is another than the one the culler last had under the key (keyedGeometry).
    std::uint64_t localKey = 0;
    std::uint64_t localVersion = 0;
    std::weak_ptr<const ShapeTriangles> keyedGeometry;
    std::shared_ptr<ShapeTriangles> geometry;
    Transform toWorld;
    TriangleMesh world;
    btTransform worldFrom;
    bool worldValid = false;
    /// The transform it had when it last entered the culling frame (seen: it entered before): a static-flagged
    /// object that moved since is culled as a moving one (local mesh + transform, no world-space copy kept).
    btTransform lastFrom;
    bool seen = false;
    std::uint64_t version = 0;  ///< of the world-space copy under `key`: bumped whenever the copy changes
    // This step.
    std::uint64_t step = 0;       ///< the last step it entered the culling frame
    std::uint32_t cullIndex = 0;  ///< its index in that step's objects
    bool reported = false;        ///< its rejection by the culler was reported
};

/// The object's world-space triangles at transform t (the culler's own mapping, toTransform + transformPoint):
/// recomputed only when t or the geometry changed.
void updateWorld(CulledObject& c, const btTransform& t);

class CullFrame {
public:
    using ProxyPair = std::pair<btBroadphaseProxy*, btBroadphaseProxy*>;

    /// Starts a step: shapes' content hashes are computed again (once per shape, however many proxies share it).
    void beginStep() { m_hashThisStep.clear(); }
    /// The culling frame of step `step` from the pairs that go through the culler.
    void build(const std::vector<ProxyPair>& candidates, std::uint64_t step, CullideFrameStats& stats);

    const std::vector<Object>& objects() const { return m_objects; }
    const std::vector<ObjectIndexPair>& pairs() const { return m_pairs; }
    const std::vector<MarginEntry>& marginEntries() const { return m_marginEntries; }
    btBroadphaseProxy* proxyOf(std::uint32_t object) const { return m_objectProxy[object]; }
    CulledObject& culled(const btBroadphaseProxy* p) { return m_culled[p]; }

    /// A proxy is gone: what was kept of it goes too.
    void forget(const btBroadphaseProxy* p) { m_culled.erase(p); }
    /// The application changed the shape's geometry in place: rebuilt on next use.
    void invalidateShape(const btCollisionShape* shape);
    /// Every proxy is gone (resetPool): nothing is kept.
    void clear();
    /// Bytes kept: shared geometry once per shape, records and world copies per object.
    CullideMemoryStats memory() const;

private:
    CulledObject& enter(btBroadphaseProxy* p, std::uint64_t step, CullideFrameStats& stats);
    std::shared_ptr<ShapeTriangles> geometryFor(CulledObject& c, const btCollisionShape* shape);
    std::uint64_t sourceHashThisStep(const btCollisionShape* shape);

    std::unordered_map<const btBroadphaseProxy*, CulledObject> m_culled;
    std::unordered_map<const btCollisionShape*, std::weak_ptr<ShapeTriangles>> m_shapes;
    /// Content hashes of the shapes seen this step (cleared every step: bounded, and shapes may come and go).
    std::unordered_map<const btCollisionShape*, std::uint64_t> m_hashThisStep;
    std::uint64_t m_nextKey = 0;
    // This step's frame.
    std::vector<Object> m_objects;
    std::vector<btBroadphaseProxy*> m_objectProxy;
    std::vector<MarginEntry> m_marginEntries;
    std::vector<ObjectIndexPair> m_pairs;
};

}  // namespace cullide::bullet
