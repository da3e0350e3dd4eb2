// Basic geometric types at the culler's boundary (Eigen, double precision).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

namespace cullide {

using Vec3 = Eigen::Vector3d;
using TriangleIndices = std::array<std::uint32_t, 3>;

/// Axis-aligned box. An empty box has min > max.
struct Aabb {
    Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
    Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

    bool isEmpty() const { return (min.array() > max.array()).any(); }
    bool isFinite() const { return min.allFinite() && max.allFinite(); }
    void grow(const Vec3& p) { min = min.cwiseMin(p); max = max.cwiseMax(p); }
    void grow(const Aabb& b) { min = min.cwiseMin(b.min); max = max.cwiseMax(b.max); }
    Aabb inflated(double r) const { return {min.array() - r, max.array() + r}; }
    Vec3 extent() const { return max - min; }
    /// Closed-interval overlap (touching boxes overlap).
    bool overlaps(const Aabb& o) const {
        return (min.array() <= o.max.array()).all() && (o.min.array() <= max.array()).all();
    }
};

/// A triangle soup in world space. Open, non-manifold, self-intersecting and degenerate triangles are valid.
struct TriangleMesh {
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
};

/// An affine map from a mesh's own frame to world space: world = linear · p + translation (rigid motions, scaling,
/// shear; a singular `linear` is allowed and yields degenerate triangles).
struct Transform {
    Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
    Vec3 translation = Vec3::Zero();
};

/// The world position of `p` under `t`, rounded exactly as the culler rounds it (and as the reference culler does,
/// so both see the same triangles): coordinate i is ((l_i0·p_0 + l_i1·p_1) + l_i2·p_2) + t_i in double precision,
/// each operation rounded to nearest, no fused multiply-add. Applications that compare contacts with their own
/// world-space geometry can call this to get bit-identical vertices.
Vec3 transformPoint(const Transform& t, const Vec3& p);

}  // namespace cullide
