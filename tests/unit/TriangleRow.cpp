#include "TriangleRow.h"

namespace cullide::test {

/// `n` separate triangles along x, listed in a scrambled order.
TriangleMesh triangleRow(std::uint32_t n) {
    TriangleMesh mesh;
    for (std::uint32_t i = 0; i < n; ++i) {
        const double x = static_cast<double>((i * 7919u) % n);
        const auto v = static_cast<std::uint32_t>(mesh.vertices.size());
        mesh.vertices.push_back(Vec3(x, 0, 0));
        mesh.vertices.push_back(Vec3(x + 0.5, 0, 0));
        mesh.vertices.push_back(Vec3(x, 0.5, 0));
        mesh.triangles.push_back({v, v + 1, v + 2});
    }
    return mesh;
}

}  // namespace cullide::test
