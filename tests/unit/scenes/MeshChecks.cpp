#include "MeshChecks.h"

#include "cullide/TriangleTest.h"
#include "cullide/scenes/Procedural.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

namespace cullide::test {
namespace {

using scenes::boundsOf;

double det(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

Aabb triangleBox(const TriangleMesh& m, const TriangleIndices& t) {
    Aabb b;
    for (const auto i : t) b.grow(m.vertices[i]);
    return b;
}

}  // namespace

std::map<Edge, int> directedEdges(const TriangleMesh& m) {
    std::map<Edge, int> edges;
    for (const auto& t : m.triangles) {
        for (int k = 0; k < 3; ++k) ++edges[{t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]}];
    }
    return edges;
}

::testing::AssertionResult isClosedOriented(const TriangleMesh& m) {
    const auto edges = directedEdges(m);
    for (const auto& [e, n] : edges) {
        if (n != 1) return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " used " << n;
        if (edges.count({e.second, e.first}) != 1) {
            return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second << " has no twin";
        }
    }
    return ::testing::AssertionSuccess();
}

double signedVolume(const TriangleMesh& m) {
    double v = 0.0;
    for (const auto& t : m.triangles) v += det(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]);
    return v / 6.0;
}

double cappedVolume(const TriangleMesh& m) {
    const auto edges = directedEdges(m);
    std::vector<Edge> boundary;
    for (const auto& [e, n] : edges) {
        if (edges.count({e.second, e.first}) == 0) boundary.push_back(e);
    }
    // Union-find over boundary vertices: one component per loop.
    std::vector<std::uint32_t> parent(m.vertices.size());
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](std::uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    };
    for (const Edge& e : boundary) parent[find(e.first)] = find(e.second);
    std::map<std::uint32_t, std::pair<Vec3, int>> centroid;
    for (const Edge& e : boundary) {
        auto& c = centroid.try_emplace(find(e.first), Vec3::Zero(), 0).first->second;
        c.first += m.vertices[e.first];
        ++c.second;
    }
    double v = signedVolume(m) * 6.0;
    for (const Edge& e : boundary) {
        const auto& c = centroid.at(find(e.first));
        v += det(m.vertices[e.second], m.vertices[e.first], c.first / c.second);
    }
    return v / 6.0;
}

bool anyIntersection(const TriangleMesh& a, const TriangleMesh& b) {
    const Aabb ba = boundsOf(a), bb = boundsOf(b);
    if (!ba.overlaps(bb)) return false;
    const Aabb region{ba.min.cwiseMax(bb.min), ba.max.cwiseMin(bb.max)};
    std::vector<std::pair<Aabb, std::uint32_t>> candidates;
    double extentSum = 0.0;
    for (std::uint32_t i = 0; i < b.triangles.size(); ++i) {
        const Aabb box = triangleBox(b, b.triangles[i]);
        if (box.overlaps(region)) {
            candidates.emplace_back(box, i);
            extentSum += box.extent().maxCoeff();
        }
    }
    if (candidates.empty()) return false;
    const double cell = std::max({extentSum / static_cast<double>(candidates.size()), region.extent().maxCoeff() / 32.0, 1e-12});
    Eigen::Vector3i dims;
    for (int k = 0; k < 3; ++k) dims[k] = static_cast<int>(region.extent()[k] / cell) + 1;
    auto cellRange = [&](const Aabb& box, Eigen::Vector3i& lo, Eigen::Vector3i& hi) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::clamp(static_cast<int>(std::floor((box.min[k] - region.min[k]) / cell)), 0, dims[k] - 1);
            hi[k] = std::clamp(static_cast<int>(std::floor((box.max[k] - region.min[k]) / cell)), 0, dims[k] - 1);
        }
    };
    std::vector<std::vector<std::uint32_t>> grid(static_cast<std::size_t>(dims.prod()));
    auto at = [&](int x, int y, int z) -> std::vector<std::uint32_t>& {
        return grid[static_cast<std::size_t>((z * dims[1] + y) * dims[0] + x)];
    };
    for (std::uint32_t c = 0; c < candidates.size(); ++c) {
        Eigen::Vector3i lo, hi;
        cellRange(candidates[c].first, lo, hi);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x) at(x, y, z).push_back(c);
    }
    for (const auto& ta : a.triangles) {
        const Aabb box = triangleBox(a, ta);
        if (!box.overlaps(region)) continue;
        Eigen::Vector3i lo, hi;
        cellRange(box, lo, hi);
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    for (const std::uint32_t c : at(x, y, z)) {
                        if (!candidates[c].first.overlaps(box)) continue;
                        const auto& tb = b.triangles[candidates[c].second];
                        if (trianglesIntersect(a.vertices[ta[0]], a.vertices[ta[1]], a.vertices[ta[2]],
                                               b.vertices[tb[0]], b.vertices[tb[1]], b.vertices[tb[2]])) {
                            return true;
                        }
                    }
    }
    return false;
}

bool sameMeshes(const std::vector<TriangleMesh>& x, const std::vector<TriangleMesh>& y) {
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (x[i].vertices != y[i].vertices || x[i].triangles != y[i].triangles) return false;
    }
    return true;
}

double shapeChange(const TriangleMesh& p, const TriangleMesh& q) {
    double worst = 0.0;
    const std::size_t n = p.vertices.size();
    for (std::size_t k = 0; k < 16; ++k) {
        const std::size_t i = (k * 7919) % n, j = (k * 104729 + n / 2) % n;
        const double dp = (p.vertices[i] - p.vertices[j]).norm(), dq = (q.vertices[i] - q.vertices[j]).norm();
        if (dp > 0.0) worst = std::max(worst, std::abs(dp - dq) / dp);
    }
    return worst;
}

}  // namespace cullide::test
