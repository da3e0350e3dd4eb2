// Scenes shared by the Bullet adapter tests: mirrored runs of the default pipeline and CULLIDE, measurement output.
#pragma once

#include "BulletTestWorld.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>

#include <array>
#include <functional>
#include <map>
#include <vector>

namespace cullide::test {

/// Skips (outside CI) or fails (CI=true) the current test when there is no GL, per GlTestSupport's policy.
#define CULLIDE_BULLET_REQUIRE_GL()                                     \
    do {                                                                \
        CULLIDE_GPU_CULLER_OR_SKIP(probeCuller_, ::cullide::Settings{}); \
    } while (false)

/// (object a, part a, triangle a, object b, part b, triangle b), a < b; -1 where a side is not a triangle.
using TriangleContactKey = std::array<int, 6>;

struct MirrorRun {
    ContactAgreement agreement;
    StepTimes defaultTimes;
    StepTimes cullideTimes;
    std::size_t cullideTrianglePairs = 0;  ///< triangle pairs (or mesh triangles) handed to the narrow phase
    std::size_t cullidePairsFromTriangles = 0;
    std::size_t fallbackPairs = 0;
    std::size_t penetrationPairs = 0;  ///< interpenetrating GImpact pair-steps given Bullet's full algorithm
    std::size_t steps = 0;
    /// Sums of the CULLIDE broadphase's per-frame breakdown.
    double buildMs = 0.0, cullMs = 0.0, recordMs = 0.0, prepassMs = 0.0, uploadMs = 0.0, gpuLevelsMs = 0.0,
           exactMs = 0.0;
    std::size_t cullerPairs = 0, cullerTriangles = 0;
    /// Triangle-level coverage: (pair, triangle pair) keys that produced a contact point under the default
    /// pipeline, and how many of them produced none under CULLIDE in the same step.
    std::size_t triangleContacts = 0;
    std::size_t triangleContactsMissing = 0;
    std::string firstTriangleMissing;
};

struct MirrorOptions {
    int steps = 240;
    /// Allowed |min distance difference| per pair (default: exact up to float noise).
    std::function<double(const std::pair<int, int>&)> tolerance = [](const std::pair<int, int>&) { return 1e-6; };
    /// Runs after every step with both worlds.
    std::function<void(int, TestWorld&, TestWorld&)> each;
    /// Before every step (after the state copy): add/remove objects in both worlds.
    std::function<void(int, TestWorld&, TestWorld&)> before;
};

/// Runs the default world step by step; before each step the CULLIDE world takes the default world's exact state
/// and runs collision detection only, so both detect contacts for identical transforms (and identical manifold
/// history). Compares the contacts of every step (reference = default pipeline).
MirrorRun runMirrored(TestWorld& reference, TestWorld& cullide, const MirrorOptions& options);

/// Prints the measurement lines of a mirror run (visible in the test log).
void printMirrorRun(const char* scene, const MirrorRun& run);

/// Position, orientation and velocities of every body, then every manifold in the dispatcher's order (the order the
/// solver reads them in) with its points: position, normal (all four components), distance, age, impulse and both
/// shape identifiers (part, triangle). Compared as bits.
std::vector<btScalar> bitState(TestWorld& w);

/// Steps `reference` and `w` side by side (not mirrored: each world runs on its own) for all `steps` and returns the
/// first step whose states (bitState) differ in any bit, or -1. From step `sleepFrom` (if not negative) every body
/// may fall asleep (sleeping thresholds raised in both worlds).
int firstDifferingStep(TestWorld& reference, TestWorld& w, int steps, int sleepFrom = -1);

/// Checks shared by the mirrored scene tests.
void expectAgreement(const MirrorRun& run, std::size_t minimumPairSteps);
/// expectAgreement, and CULLIDE's triangle lists fed the narrow phase with no pair left to Bullet's full path.
void expectCulledAgreement(const MirrorRun& run, std::size_t minimumPairSteps);

}  // namespace cullide::test
