// Procedural meshes: tori, open cylinders, UV spheres, boxes. Closed shapes are consistently oriented with outward
// normals (counter-clockwise seen from outside), so their signed volume is positive.
#include "cullide/scenes/Procedural.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace cullide::scenes {

namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kPi = 3.1415926535897932384626433832795;

void requireAtLeast(int value, int minimum, const char* what) {
    if (value < minimum) {
        throw std::invalid_argument(std::string(what) + " must be at least " + std::to_string(minimum) + ", got " +
                                    std::to_string(value));
    }
}

void requireLength(double value, const char* what) {
    if (!std::isfinite(value) || value < 0.0) {
        throw std::invalid_argument(std::string(what) + " must be finite and non-negative");
    }
}

std::uint32_t u32(int v) { return static_cast<std::uint32_t>(v); }

}  // namespace

TriangleMesh makeTorus(double R, double r, int nu, int nv) {
    requireLength(R, "torus major radius");
    requireLength(r, "torus minor radius");
    requireAtLeast(nu, 3, "torus nu");
    requireAtLeast(nv, 3, "torus nv");
    TriangleMesh m;
    m.vertices.reserve(static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv));
    for (int i = 0; i < nu; ++i) {
        const double u = kTwoPi * i / nu;
        for (int j = 0; j < nv; ++j) {
            const double v = kTwoPi * j / nv;
            const double rr = R + r * std::cos(v);
            m.vertices.emplace_back(rr * std::cos(u), rr * std::sin(u), r * std::sin(v));
        }
    }
    auto id = [nv](int i, int j) { return u32(i * nv + j); };
    m.triangles.reserve(2 * static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv));
    for (int i = 0; i < nu; ++i) {
        const int i1 = (i + 1) % nu;
        for (int j = 0; j < nv; ++j) {
            const int j1 = (j + 1) % nv;
            // d/du x d/dv points outwards.
            m.triangles.push_back({id(i, j), id(i1, j), id(i1, j1)});
            m.triangles.push_back({id(i, j), id(i1, j1), id(i, j1)});
        }
    }
    return m;
}

TriangleMesh makeOpenCylinder(double radius, double height, int segments, int rings) {
    requireLength(radius, "cylinder radius");
    requireLength(height, "cylinder height");
    requireAtLeast(segments, 3, "cylinder segments");
    requireAtLeast(rings, 1, "cylinder rings");
    TriangleMesh m;
    m.vertices.reserve(static_cast<std::size_t>(segments) * static_cast<std::size_t>(rings + 1));
    for (int j = 0; j <= rings; ++j) {
        const double z = -0.5 * height + height * j / rings;
        for (int i = 0; i < segments; ++i) {
            const double u = kTwoPi * i / segments;
            m.vertices.emplace_back(radius * std::cos(u), radius * std::sin(u), z);
        }
    }
    auto id = [segments](int i, int j) { return u32(j * segments + i); };
    m.triangles.reserve(2 * static_cast<std::size_t>(segments) * static_cast<std::size_t>(rings));
    for (int j = 0; j < rings; ++j) {
        for (int i = 0; i < segments; ++i) {
            const int i1 = (i + 1) % segments;
            m.triangles.push_back({id(i, j), id(i1, j), id(i1, j + 1)});
            m.triangles.push_back({id(i, j), id(i1, j + 1), id(i, j + 1)});
        }
    }
    return m;
}

TriangleMesh makeSphere(double radius, int nu, int nv) {
    requireLength(radius, "sphere radius");
    requireAtLeast(nu, 3, "sphere nu");
    requireAtLeast(nv, 2, "sphere nv");
    TriangleMesh m;
    // North pole, nv-1 rings of nu vertices, south pole.
    m.vertices.reserve(2 + static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv - 1));
    m.vertices.emplace_back(0.0, 0.0, radius);
    for (int k = 1; k < nv; ++k) {
        const double theta = kPi * k / nv;
        for (int i = 0; i < nu; ++i) {
            const double phi = kTwoPi * i / nu;
            m.vertices.emplace_back(radius * std::sin(theta) * std::cos(phi),
                                    radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta));
        }
    }
    m.vertices.emplace_back(0.0, 0.0, -radius);
    const auto south = u32(nu * (nv - 1) + 1);
    auto id = [nu](int k, int i) { return u32(1 + (k - 1) * nu + (i % nu)); };
    m.triangles.reserve(2 * static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv - 1));
    for (int i = 0; i < nu; ++i) m.triangles.push_back({0, id(1, i), id(1, i + 1)});
    for (int k = 1; k + 1 < nv; ++k) {
        for (int i = 0; i < nu; ++i) {
            // d/dtheta x d/dphi points outwards.
            m.triangles.push_back({id(k, i), id(k + 1, i), id(k + 1, i + 1)});
            m.triangles.push_back({id(k, i), id(k + 1, i + 1), id(k, i + 1)});
        }
    }
    for (int i = 0; i < nu; ++i) m.triangles.push_back({id(nv - 1, i), south, id(nv - 1, i + 1)});
    return m;
}

TriangleMesh makeBox(const Vec3& halfExtents) {
    if (!halfExtents.allFinite() || (halfExtents.array() < 0.0).any()) {
        throw std::invalid_argument("box half extents must be finite and non-negative");
    }
    TriangleMesh m;
    for (int k = 0; k < 8; ++k) {
        m.vertices.emplace_back((k & 1) ? halfExtents.x() : -halfExtents.x(),
                                (k & 2) ? halfExtents.y() : -halfExtents.y(),
                                (k & 4) ? halfExtents.z() : -halfExtents.z());
    }
    // Vertex k has bit 0 = +x, bit 1 = +y, bit 2 = +z. Each face: two triangles, counter-clockwise from outside.
    m.triangles = {
        {0, 2, 3}, {0, 3, 1},  // -z
        {4, 5, 7}, {4, 7, 6},  // +z
        {0, 1, 5}, {0, 5, 4},  // -y
        {2, 6, 7}, {2, 7, 3},  // +y
        {0, 4, 6}, {0, 6, 2},  // -x
        {1, 3, 7}, {1, 7, 5},  // +x
    };
    return m;
}

void transformMesh(TriangleMesh& mesh, const Eigen::Affine3d& t) {
    for (Vec3& p : mesh.vertices) p = t * p;
}

Aabb boundsOf(const TriangleMesh& mesh) {
    Aabb box;
    for (const Vec3& p : mesh.vertices) box.grow(p);
    return box;
}

}  // namespace cullide::scenes
