#include "cullide_bullet/CullideStats.h"

namespace cullide {

// A field added to CullideDispatchStats must be added below too: this fails to compile until the count is updated.
static_assert(sizeof(CullideDispatchStats) == 19 * sizeof(std::size_t) + sizeof(double),
              "CullideDispatchStats changed: update operator+=");

CullideDispatchStats& CullideDispatchStats::operator+=(const CullideDispatchStats& other) {
    pairsDispatched += other.pairsDispatched;
    apartPairs += other.apartPairs;
    threadedPairs += other.threadedPairs;
    cullidePairs += other.cullidePairs;
    trianglePairs += other.trianglePairs;
    clearedPairs += other.clearedPairs;
    penetrationPairs += other.penetrationPairs;
    fallbackPairs += other.fallbackPairs;
    convexPairs += other.convexPairs;
    concavePairs += other.concavePairs;
    convexCandidates += other.convexCandidates;
    convexTriangles += other.convexTriangles;
    convexUnchecked += other.convexUnchecked;
    threadedConvexPairs += other.threadedConvexPairs;
    threadedMeshPairs += other.threadedMeshPairs;
    threadedTasks += other.threadedTasks;
    planePairs += other.planePairs;
    planeVertices += other.planeVertices;
    planeVerticesTested += other.planeVerticesTested;
    dispatchMs += other.dispatchMs;
    return *this;
}

}  // namespace cullide
