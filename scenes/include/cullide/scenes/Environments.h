// The paper's environments and the seeded random scenes used by tests, benchmarks and demos. All deterministic
// for a seed.
#pragma once

#include "cullide/Types.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace cullide::scenes {

/// A sequence of frames of world-space meshes. Object counts and triangle counts may change between frames.
class Environment {
public:
    virtual ~Environment() = default;
    /// Advances to frame `frame` (0-based; frames may be visited in any order) and returns its meshes.
    virtual const std::vector<TriangleMesh>& frame(int frame) = 0;
    virtual std::string name() const = 0;
};

/// Environment 1: `count` deforming open cylinders (~trianglesPerObject each) moving in a unit box at ~5-6% density.
std::unique_ptr<Environment> makeEnv1(std::uint64_t seed, int count = 100, int trianglesPerObject = 200);
/// Environment 2: `count` deforming tori of ~trianglesPerObject each moving in a box (~6-8% density).
std::unique_ptr<Environment> makeEnv2(std::uint64_t seed, int count = 6, int trianglesPerObject = 20000);
/// Environment 3: bunny vs dragon interpenetrating (rigid, moving along a fixed path). Meshes are read from
/// `dataDir` (bunny00.off, ChineseDragon-10kv.off); when missing, procedural stand-ins are used and
/// `usedStandIns` is set. With `deformBunny` the bunny deforms every frame.
std::unique_ptr<Environment> makeEnv3(const std::string& dataDir, bool deformBunny, bool* usedStandIns = nullptr);

enum class PaperModel { Bunny, Dragon, Armadillo };
/// One of the paper's models as read from `dataDir` (bunny00.off 75K, ChineseDragon-10kv.off 20K, armadillo.off
/// 52K triangles; in the file's own frame and units), or, when the file is missing, a procedural stand-in of about
/// the same triangle count (a lumpy sphere, a bumpy torus-knot tube) and `usedStandIn` is set. A present but
/// malformed file throws io::ParseError.
TriangleMesh paperModel(const std::string& dataDir, PaperModel model, bool* usedStandIn = nullptr);

struct RandomSceneOptions {
    int objects = 10;
    int minTriangles = 20;
    int maxTriangles = 200;
    double boxSize = 1.0;      ///< objects are placed in [0, boxSize]^3
    double objectSize = 0.25;  ///< typical object diameter
    bool soups = true;         ///< mix in random triangle soups and open meshes besides closed shapes
};
/// A random frame of meshes (closed shapes, open meshes, random soups), seeded.
std::vector<TriangleMesh> makeRandomScene(std::uint64_t seed, const RandomSceneOptions& options);

/// Directory where set-up put the real meshes (env CULLIDE_DATA_DIR, else "<source>/data/meshes").
std::string defaultDataDir();

}  // namespace cullide::scenes
