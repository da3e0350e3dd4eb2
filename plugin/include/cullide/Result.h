// What one culling frame produces: the PCS, the potentially colliding pairs with their exact triangle pairs,
// diagnostics for rejected objects and per-stage statistics.
#pragma once

#include "cullide/Stats.h"

#include <cstdint>
#include <string>
#include <vector>

namespace cullide {

struct TrianglePair {
    std::uint32_t a = 0;  ///< triangle index in object ObjectPair::a
    std::uint32_t b = 0;  ///< triangle index in object ObjectPair::b
    friend bool operator==(const TrianglePair& x, const TrianglePair& y) { return x.a == y.a && x.b == y.b; }
    friend bool operator<(const TrianglePair& x, const TrianglePair& y) {
        return x.a != y.a ? x.a < y.a : x.b < y.b;
    }
};

/// A potentially colliding object pair (a < b). For two meshes, `triangles` lists every intersecting (or, with
/// margin > 0, within-margin) triangle pair exactly once, sorted; it may be empty. Pairs involving a box-only
/// proxy have no triangles (hasTriangles == false): the caller's narrow phase decides.
struct ObjectPair {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    bool hasTriangles = false;
    std::vector<TrianglePair> triangles;
};

/// An object the culler refused (it takes part in nothing; every other object is unaffected).
struct ObjectDiagnostic {
    std::uint32_t object = 0;
    std::string message;
};

struct Result {
    /// Object-level PCS: objects that may collide with some other object (sorted).
    std::vector<std::uint32_t> pcs;
    /// Potentially colliding object pairs (sorted by (a, b)).
    std::vector<ObjectPair> pairs;
    /// Triangle-level PCS, indexed by object: the triangles that survived culling (sorted; empty for box proxies,
    /// rejected objects and objects culled whole). A superset of the triangles named in `pairs`. Unlike `pairs`,
    /// which is a function of the input alone in reliable mode, its size shows how much the culling levels removed
    /// and so depends on the pipeline and device (GPU levels or the CPU pre-pass). The reference culler reports the
    /// triangles of its pairs (the smallest possible PCS).
    std::vector<std::vector<std::uint32_t>> pcsTriangles;
    std::vector<ObjectDiagnostic> rejected;
    Stats stats;

    void clear();
};

}  // namespace cullide
