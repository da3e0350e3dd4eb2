// The hand-off from CullideBroadphase to CullideCollisionDispatcher: one record per culled pair of the step.
//
// The contract. calculateOverlappingPairs() clears every record and makes one for each pair that went through the
// culler (or skipped it because it was recently found interpenetrating), keyed by the two proxies' unique ids and
// holding the proxies, the objects' shapes and world transforms at that moment, and the verdict: `pruned` (proven
// farther apart than the culler's margin: no contact this step), `interpenetrating` (Bullet's full algorithm), or
// the surviving triangles. A record is a statement about that geometry only: find() returns it only while both
// objects still have the recorded proxies, shapes and world transforms (bit for bit; a compound's child wrapper may
// use its compound's record, the kept mesh triangles being a superset of those near any child). Anything else — an
// object moved or reshaped between the broadphase and the narrow phase, a pair that did not go through the culler —
// gets no record, and the dispatcher runs Bullet's own algorithm: a stale record can never lose a contact. A record
// lives until the next step or until a proxy of its pair is destroyed.
#pragma once

#include "broadphase/CullFrame.h"
#include "broadphase/PairTriangles.h"
#include "cullide/Result.h"
#include "cullide_bullet/CullideStats.h"

#include <BulletCollision/BroadphaseCollision/btBroadphaseProxy.h>

#include <cstdint>
#include <unordered_map>
#include <vector>

class btCollisionObjectWrapper;

namespace cullide::bullet {

class PairRecords {
public:
    /// A GImpact pair found interpenetrating (deep-penetration fallback on) runs Bullet's full algorithm, which
    /// reads nothing the culler computes: it skips the culler for this many following steps, then is culled again.
    /// Interpenetration persists over steps in piles and fractures; a pair that separated costs at most this many
    /// steps of Bullet's full algorithm, never a contact.
    static constexpr std::uint64_t kPenetrationRecheck = 4;

    /// Starts step `step`: no records; pairs whose skipping ended are forgotten (all of them without the fallback).
    void beginStep(std::uint64_t step, bool deepPenetrationFallback);
    /// Whether the pair skips the culler this step (found interpenetrating within kPenetrationRecheck steps).
    bool recentlyPenetrating(const btBroadphaseProxy* a, const btBroadphaseProxy* b) const;
    /// Records the pair as interpenetrating without culling it.
    void recordPenetrating(const btBroadphaseProxy* a, const btBroadphaseProxy* b);
    /// Records the culler's verdicts on frame.pairs(): kept pairs with their surviving triangles, every other pair
    /// (provably farther apart than the margin, or with an object the culler rejected) as pruned.
    void recordVerdicts(const Result& result, CullFrame& frame, bool deepPenetrationFallback, CullideFrameStats& stats);

    /// The record of the two wrapped objects' pair while it holds (see the contract above); `swapped` when w0 is the
    /// record's second object.
    const PairTriangles* find(const btCollisionObjectWrapper* w0, const btCollisionObjectWrapper* w1,
                              bool& swapped) const;

    /// A proxy is gone: its pairs' records too.
    void forgetProxy(const btBroadphaseProxy* p);
    void clear() { m_records.clear(); }

private:
    struct Record {
        const btBroadphaseProxy* first = nullptr;  ///< lower unique id
        const btBroadphaseProxy* second = nullptr;
        const btCollisionShape* shapeFirst = nullptr;
        const btCollisionShape* shapeSecond = nullptr;
        btTransform transformFirst;
        btTransform transformSecond;
        PairTriangles triangles;
    };
    /// The box of triangle t of a world mesh, computed once per record side (stamped cache).
    struct TriangleBoxes {
        std::vector<Aabb> boxes;
        std::vector<std::uint32_t> stamp;
        std::uint32_t current = 0;
        void begin(std::size_t triangles);
        const Aabb& of(const TriangleMesh& m, std::uint32_t t);
    };

    static Record recordFor(const btBroadphaseProxy* pa, const btBroadphaseProxy* pb);
    void recordKept(const ObjectPair& op, CullFrame& frame, bool deepPenetrationFallback, CullideFrameStats& stats);
    bool nearGImpactPairs(const CulledObject& ca, const CulledObject& cb, const ObjectPair& op, bool flip,
                          bool deepPenetrationFallback, std::vector<BulletTrianglePair>& out);

    std::unordered_map<std::uint64_t, Record> m_records;
    /// Pairs found interpenetrating: the last step in which they skip the culler (kPenetrationRecheck).
    std::unordered_map<std::uint64_t, std::uint64_t> m_penetratingUntil;
    std::uint64_t m_step = 0;
    TriangleBoxes m_boxesA, m_boxesB;
};

}  // namespace cullide::bullet
