// The statistics the Bullet adapter reports: per step of the broadphase (CullideBroadphase::getLastFrameStats), of
// what the broadphase keeps between steps (CullideBroadphase::getMemoryStats), and of the narrow phase
// (CullideCollisionDispatcher::getLastStepStats, getTotalStats).
#pragma once

#include "cullide/Stats.h"

#include <cstddef>
#include <string>

namespace cullide {

/// One calculateOverlappingPairs() of CullideBroadphase.
struct CullideFrameStats {
    std::size_t proxies = 0;             ///< broadphase proxies (collision objects) at the end of the step
    std::size_t objectPairs = 0;         ///< pairs in the object level's pair cache
    std::size_t culledPairs = 0;         ///< ... of which went through the culler (a culling switch covers them)
    std::size_t prunedPairs = 0;         ///< ... of which the culler proved farther apart than the margin
    std::size_t cullerPairs = 0;         ///< culled pairs the culler kept
    std::size_t culledObjects = 0;       ///< objects handed to the culler (those of culled pairs)
    std::size_t meshObjects = 0;         ///< ... of which with triangle geometry
    std::size_t triangles = 0;           ///< triangles handed to the culler
    std::size_t rejectedObjects = 0;     ///< parked (non-finite AABB) or rejected by the culler this step
    std::size_t pcsTriangles = 0;        ///< triangles that survived culling (the triangle-level PCS), all objects
    std::size_t trianglePairs = 0;       ///< surviving triangle pairs kept for the dispatcher
    std::size_t interpenetratingPairs = 0;  ///< GImpact pairs whose meshes intersect (setDeepPenetrationFallback)
    /// GImpact pairs that interpenetrated in one of the last 4 steps: not culled, Bullet's full algorithm runs them
    /// (culled again after 4 steps).
    std::size_t penetratingSkipped = 0;
    double margin = 0.0;                 ///< the culler's distance margin this step
    double objectLevelMs = 0.0;          ///< the object level's calculateOverlappingPairs
    double buildMs = 0.0;                ///< finding the culled pairs and building the culling frame
    double cullMs = 0.0;                 ///< the culler's run
    double recordMs = 0.0;               ///< the per-pair records for the dispatcher
    double totalMs = 0.0;                ///< the whole calculateOverlappingPairs
    Stats culler;                        ///< the culler's own statistics of its run (cullide/Stats.h)
};

/// What CullideBroadphase keeps between steps for the objects of culled pairs: local triangle geometry once per
/// shape, however many bodies share it, and per object its record (transform, keys) plus a world-space copy of its
/// triangles where one is kept (resting static objects; with GImpact pair culling, objects whose pairs the broadphase
/// tests itself). Heap bytes of the containers (capacity), not counting the culler's own caches.
struct CullideMemoryStats {
    std::size_t shapes = 0;               ///< shapes with local geometry (each held once)
    std::size_t sharedGeometryBytes = 0;  ///< their vertices, triangles and Bullet ids, in both precisions
    std::size_t objects = 0;              ///< objects kept
    std::size_t objectBytes = 0;          ///< their records and world-space copies
    std::size_t worldCopies = 0;          ///< objects holding a world-space copy
};

/// What Culling::Auto decided for one kind of pair (CullideBroadphase::getCullingDecision).
struct CullingDecision {
    /// "culled" or "not culled" (the switch is On or Off), "not trialled" (Auto where it does not trial: no hardware
    /// GL device), "waiting" (Auto, no trial yet: no such pairs, or the culler is still being made), "measuring",
    /// "on" or "off" (the last trial's outcome).
    std::string state;
    bool culled = false;        ///< culled in the step under way
    double unculledMs = 0.0;    ///< the last trial's step without culling the kind (culling + narrow phase), ms
    double culledMs = 0.0;      ///< ... and its timed step with it culled (0 before a trial completes)
    std::size_t abandonedTrials = 0;  ///< trial steps whose culler ran past its budget (all kinds)
};

/// One or more dispatchAllCollisionPairs() of CullideCollisionDispatcher. Every count is of pairs of the dispatched
/// pair cache unless it says otherwise; "culled" pairs are those a culling switch of the broadphase covers.
struct CullideDispatchStats {
    std::size_t pairsDispatched = 0;     ///< pairs in the dispatched pair caches
    /// Pairs whose broadphase boxes were farther apart than their contact breaking threshold: their algorithm was
    /// not called, their manifolds got what the algorithm would give them with no point found
    std::size_t apartPairs = 0;
    /// Pairs handed to the narrow-phase threads to run their Bullet algorithm (convex GJK pairs, convex against a
    /// BVH mesh or heightfield), while no application hook is installed and it pays
    std::size_t threadedPairs = 0;

    // ---- culled pairs (the broadphase's record of the step: CULLIDE's surviving triangles) ----
    std::size_t cullidePairs = 0;        ///< culled pairs processed from CULLIDE's triangle lists
    std::size_t trianglePairs = 0;       ///< ... their triangle pairs (GImpact-GImpact) or mesh triangles handed over
    /// ... of which had no surviving triangle (GImpact-convex, convex-mesh: no point this step), or whose surviving
    /// triangle pairs made no point (GImpact-GImpact: Bullet's contacts instead, see CulledKind::GImpactPair)
    std::size_t clearedPairs = 0;
    /// ... of which were interpenetrating GImpact pairs, given Bullet's full algorithm
    /// (CullideBroadphase::setDeepPenetrationFallback)
    std::size_t penetrationPairs = 0;
    /// Pairs of a kind that can read CULLIDE's triangles but ran Bullet's full algorithm (or, for GImpact-GImpact,
    /// its reproduction with Bullet's contacts): not culled this step, or of a shape the culled path does not read
    std::size_t fallbackPairs = 0;

    // ---- GImpact mesh against a convex or concave shape (Bullet's per-triangle loop minus triangles out of reach) ----
    std::size_t convexPairs = 0;         ///< GImpact mesh against a convex shape (not a compound)
    /// GImpact mesh against a concave shape (triangle mesh, heightfield) not culled: for each concave triangle within
    /// reach, the GImpact part's candidates within reach of it
    std::size_t concavePairs = 0;
    std::size_t convexCandidates = 0;    ///< triangles of Bullet's box queries (both kinds of pair above)
    std::size_t convexTriangles = 0;     ///< ... of which within reach of the other shape: run through GJK
    /// ... of which taken without a per-triangle test: their mesh part lay wholly within reach of the convex shape
    std::size_t convexUnchecked = 0;
    /// GImpact-convex pairs whose triangles were collided ahead on the narrow-phase threads, their points then added
    /// in Bullet's order
    std::size_t threadedConvexPairs = 0;

    // ---- GImpact mesh against GImpact mesh with Bullet's contacts ----
    std::size_t threadedMeshPairs = 0;   ///< pairs whose contacts were computed ahead on the narrow-phase threads
    std::size_t threadedTasks = 0;       ///< ... and their search parts (a large pair's search is cut into several)

    // ---- GImpact mesh against a static plane (Bullet's vertex loop, most vertices ruled out by a bound first) ----
    std::size_t planePairs = 0;          ///< such pairs
    std::size_t planeVertices = 0;       ///< vertices of their parts whose box reached the plane (Bullet maps each)
    std::size_t planeVerticesTested = 0; ///< ... of which Bullet's test ran on

    double dispatchMs = 0.0;             ///< wall time in dispatchAllCollisionPairs

    /// Adds every count and time of `other`.
    CullideDispatchStats& operator+=(const CullideDispatchStats& other);
    void reset() { *this = CullideDispatchStats{}; }
};

}  // namespace cullide
