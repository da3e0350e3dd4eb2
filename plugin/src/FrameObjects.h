// Validation of a frame's objects and the CPU box pre-pass shared by the GPU and the reference culler.
#pragma once

#include "cullide/TaskPool.h"
#include "cullide/Object.h"
#include "cullide/Result.h"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace cullide {

struct ValidatedObject {
    bool valid = false;
    bool isMesh = false;
    Aabb box;  ///< world bounds inflated by margin / 2 (empty for meshes without triangles)
    /// A mesh that came with a transform and passed the checks in its own frame: `localBox` is its box there (not
    /// inflated), which placeTransformed maps to `box` under any transform (StaticMeshCache keeps it while the
    /// transform changes).
    bool localChecked = false;
    Aabb localBox;
};

/// Checks every object (finite coordinates, indices in range, finite non-empty proxy boxes); invalid ones go to
/// `rejected` with a message (the first defect of the mesh, in triangle order). A mesh's box is that of its
/// vertices when all are finite, else of the vertices its triangles use. Boxes are inflated by margin / 2,
/// so two boxes overlap iff their L-infinity distance is at most the margin. With a pool, meshes are checked on
/// every worker; the result is the same.
/// An object with a transform is checked in its own frame (the same messages) and its box is the world box of
/// transformedBounds(); a non-finite transform, or one that maps the box beyond the double range, rejects it.
/// Objects with `known[i]` set are skipped (their entry is left invalid and unchecked: the caller has their
/// result from an earlier frame).
std::vector<ValidatedObject> validateObjects(const std::vector<Object>& objects, double margin,
                                             std::vector<ObjectDiagnostic>& rejected, TaskPool* pool = nullptr,
                                             const std::vector<std::uint8_t>* known = nullptr);

/// The transform step of a mesh checked in its own frame (v.localChecked): v.box becomes the world box of
/// transformedBounds(t, v.localBox) inflated by margin / 2, and v is valid; or returns why `t` rejects it (not finite,
/// or it maps the mesh beyond the double range), and v is left invalid with an empty box.
const char* placeTransformed(const Transform& t, double margin, ValidatedObject& v);

/// All pairs (a < b) of valid objects whose boxes overlap, sorted: sweep and prune along the widest axis.
std::vector<std::pair<std::uint32_t, std::uint32_t>> overlappingPairs(const std::vector<ValidatedObject>& objects);

/// The pairs of `only` (see Culler::run: sorted, first < second < objects.size(), else std::invalid_argument) whose
/// objects are both valid and whose boxes overlap: overlappingPairs() restricted to them, sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> listedOverlappingPairs(
    const std::vector<ValidatedObject>& objects, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& only);

/// Throws std::invalid_argument unless `only` is sorted, without repeats, each first < second < objectCount.
void checkPairList(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& only, std::size_t objectCount);

/// How far apart two groups of objects may be and still share one view: a cluster's box extent (largest side) stays
/// within this factor of the larger of its parts' extents.
constexpr double kClusterSpread = 2.0;

/// Groups of objects that can meet, for the visibility levels: the connected components of the overlap graph
/// `pairs` over the objects with `member` set (each component as its sorted object indices), merged greedily in the
/// order of their smallest object while the merged box stays within kClusterSpread of the larger part's extent. Two
/// objects in different clusters have disjoint boxes (they cannot collide), and no cluster spans empty space much
/// larger than what it holds: a view fitted to a cluster spends its pixels and its float precision on its objects.
/// Clusters come sorted by their smallest object; objects with `member` clear belong to none.
std::vector<std::vector<std::uint32_t>> clustersOf(const std::vector<std::uint8_t>& member,
                                                   const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                                                   const std::vector<ValidatedObject>& objects);

/// True when some triangle's box, inflated by margin / 2, overlaps `box` (already inflated by margin / 2): the
/// deterministic test for pairs with a box-only proxy (their narrow phase is the caller's).
bool meshTouchesBox(const TriangleMesh& mesh, const Aabb& box, double margin);

/// Box of triangle t of `mesh`, inflated by `inflate`.
inline Aabb triangleBounds(const TriangleMesh& mesh, std::uint32_t t, double inflate = 0.0) {
    const TriangleIndices& tri = mesh.triangles[t];
    const Vec3& p = mesh.vertices[tri[0]];
    const Vec3& q = mesh.vertices[tri[1]];
    const Vec3& r = mesh.vertices[tri[2]];
    Aabb b;
    for (int k = 0; k < 3; ++k) {
        b.min[k] = std::min(std::min(p[k], q[k]), r[k]) - inflate;
        b.max[k] = std::max(std::max(p[k], q[k]), r[k]) + inflate;
    }
    return b;
}

}  // namespace cullide
