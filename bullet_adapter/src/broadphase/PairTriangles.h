// What the broadphase hands to the dispatcher for one culled pair (PairRecords.h states when it may be used).
#pragma once

#include <LinearMath/btVector3.h>

#include <vector>

namespace cullide {

/// A triangle as Bullet's narrow phase names it: part = GImpact mesh part or btStridingMeshInterface subpart,
/// index = triangle index within that part.
struct BulletTriangle {
    int part = 0;
    int index = 0;
    friend bool operator==(const BulletTriangle& x, const BulletTriangle& y) {
        return x.part == y.part && x.index == y.index;
    }
    friend bool operator<(const BulletTriangle& x, const BulletTriangle& y) {
        return x.part != y.part ? x.part < y.part : x.index < y.index;
    }
};

struct BulletTrianglePair {
    BulletTriangle a;  ///< triangle of the first object of the pair
    BulletTriangle b;  ///< triangle of the second object
};

/// What CULLIDE kept for one object pair in the last calculateOverlappingPairs().
struct PairTriangles {
    /// GImpact-GImpact: surviving candidate triangle pairs (within the culling margin d), sorted by (a.part, b.part,
    /// a.index, b.index). The dispatcher hands Bullet's triangle routine those that Bullet's own BVH search would
    /// also produce (overlapping quantized leaf boxes).
    std::vector<BulletTrianglePair> pairs;
    /// GImpact-GImpact: the two meshes intersect (a surviving triangle pair shares a point, exact test) and the
    /// deep-penetration fallback is on: the dispatcher runs Bullet's full GImpact algorithm for the pair this step,
    /// so the penetration contacts that GImpact derives from distant triangle pairs are kept.
    bool interpenetrating = false;
    /// Convex hull, compound or GImpact mesh against a triangle mesh: the mesh's surviving triangles, sorted, and
    /// their vertices in the mesh's local frame exactly as Bullet's processAllTriangles yields them (3 per triangle).
    std::vector<BulletTriangle> meshTriangles;
    std::vector<btVector3> meshTriangleVertices;
    /// The culler proved the pair farther apart than its margin (or rejected one of its objects): no triangle of it
    /// can make a contact point this step, and the dispatcher makes none (the lists above are empty).
    bool pruned = false;
};

}  // namespace cullide
