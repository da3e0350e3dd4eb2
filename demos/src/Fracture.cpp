#include "cullide/demo/Fracture.h"

#include <LinearMath/btConvexHullComputer.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace cullide::demo {

namespace {

/// Half-space n.x <= d.
struct Plane {
    Vec3 n;
    double d;
};

using Polygon = std::vector<Vec3>;

/// Sutherland-Hodgman: the part of `poly` in the half-space. Points on the plane are kept.
void clip(const Polygon& poly, const Plane& plane, Polygon& out) {
    out.clear();
    const std::size_t n = poly.size();
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3& p = poly[i];
        const Vec3& q = poly[(i + 1) % n];
        const double dp = plane.n.dot(p) - plane.d;
        const double dq = plane.n.dot(q) - plane.d;
        if (dp <= 0) out.push_back(p);
        if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
            const double t = dp / (dp - dq);
            out.push_back(p + t * (q - p));
        }
    }
}

double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace

std::vector<Vec3> fractureSites(const Aabb& bounds, const Vec3& impact, int count, std::uint64_t seed) {
    if (count < 1) throw std::invalid_argument("fractureSites: count must be >= 1");
    if (bounds.isEmpty() || !bounds.isFinite() || !impact.allFinite())
        throw std::invalid_argument("fractureSites: bounds and impact must be finite");
    std::mt19937_64 rng(seed);
    const Vec3 extent = bounds.extent();
    const double radius = 0.25 * extent.maxCoeff();
    std::vector<Vec3> sites;
    sites.reserve(static_cast<std::size_t>(count));
    for (int i = 0; i < count; ++i) {
        if (i % 2 == 0) {
            // Near the impact: a random direction, a radius biased towards the centre.
            Vec3 dir(uniform01(rng) * 2 - 1, uniform01(rng) * 2 - 1, uniform01(rng) * 2 - 1);
            if (dir.norm() < 1e-9) dir = Vec3::UnitX();
            const double r = radius * std::pow(uniform01(rng), 1.5);
            sites.push_back(impact + r * dir.normalized());
        } else {
            sites.push_back(bounds.min + Vec3(uniform01(rng), uniform01(rng), uniform01(rng)).cwiseProduct(extent));
        }
    }
    return sites;
}

std::vector<TriangleMesh> voronoiCut(const TriangleMesh& mesh, const std::vector<Vec3>& sites, double gap) {
    if (!(gap >= 0) || !std::isfinite(gap)) throw std::invalid_argument("voronoiCut: gap must be finite and >= 0");
    for (const Vec3& s : sites)
        if (!s.allFinite()) throw std::invalid_argument("voronoiCut: sites must be finite");
    std::vector<TriangleMesh> pieces(sites.size());
    if (sites.empty()) return pieces;

    Aabb bounds;
    for (const Vec3& v : mesh.vertices)
        if (v.allFinite()) bounds.grow(v);
    const double size = bounds.isEmpty() ? 1.0 : std::max(bounds.extent().maxCoeff(), 1e-300);
    const double minDoubleArea = 2e-12 * size * size;

    // Cell i = intersection of the half-spaces towards i of every bisector (i, j), each moved by gap / 2.
    const std::size_t cells = sites.size();
    std::vector<std::vector<Plane>> cellPlanes(cells);
    for (std::size_t i = 0; i < cells; ++i)
        for (std::size_t j = 0; j < cells; ++j) {
            if (i == j) continue;
            const Vec3 n = sites[j] - sites[i];
            const double len = n.norm();
            if (len == 0) continue;  // duplicate sites: the lower index keeps the cell (see below)
            cellPlanes[i].push_back({n / len, (n / len).dot(0.5 * (sites[i] + sites[j])) - 0.5 * gap});
        }
    auto nearest = [&](const Vec3& p) {
        std::size_t best = 0;
        double bestD = (p - sites[0]).squaredNorm();
        for (std::size_t i = 1; i < cells; ++i) {
            const double d = (p - sites[i]).squaredNorm();
            if (d < bestD) bestD = d, best = i;
        }
        return best;
    };
    auto inside = [&](std::size_t cell, const Vec3& p) {
        for (const Plane& pl : cellPlanes[cell])
            if (pl.n.dot(p) > pl.d) return false;
        return true;
    };
    auto emit = [&](TriangleMesh& piece, const Polygon& poly) {
        for (std::size_t k = 1; k + 1 < poly.size(); ++k) {
            if ((poly[k] - poly[0]).cross(poly[k + 1] - poly[0]).norm() <= minDoubleArea) continue;
            const auto base = static_cast<std::uint32_t>(piece.vertices.size());
            piece.vertices.push_back(poly[0]);
            piece.vertices.push_back(poly[k]);
            piece.vertices.push_back(poly[k + 1]);
            piece.triangles.push_back({base, base + 1, base + 2});
        }
    };
    std::vector<std::uint8_t> duplicate(cells, 0);
    for (std::size_t i = 0; i < cells; ++i)
        for (std::size_t j = 0; j < i; ++j)
            if (sites[i] == sites[j]) duplicate[i] = 1;

    Polygon poly, scratch;
    const std::size_t nv = mesh.vertices.size();
    for (const TriangleIndices& t : mesh.triangles) {
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) continue;
        const Vec3& a = mesh.vertices[t[0]];
        const Vec3& b = mesh.vertices[t[1]];
        const Vec3& c = mesh.vertices[t[2]];
        if (!a.allFinite() || !b.allFinite() || !c.allFinite()) continue;
        const std::size_t ca = nearest(a);
        if (ca == nearest(b) && ca == nearest(c) && inside(ca, a) && inside(ca, b) && inside(ca, c)) {
            emit(pieces[ca], {a, b, c});  // the common case: wholly inside one (convex) cell
            continue;
        }
        for (std::size_t cell = 0; cell < cells; ++cell) {
            if (duplicate[cell]) continue;
            poly = {a, b, c};
            for (const Plane& pl : cellPlanes[cell]) {
                clip(poly, pl, scratch);
                poly.swap(scratch);
                if (poly.size() < 3) break;
            }
            if (poly.size() >= 3) emit(pieces[cell], poly);
        }
    }
    return pieces;
}

MassProperties hullMassProperties(const std::vector<Vec3>& points, double density, double minThickness) {
    if (!(density > 0) || !std::isfinite(density)) throw std::invalid_argument("hullMassProperties: density must be > 0");
    if (!(minThickness > 0) || !std::isfinite(minThickness))
        throw std::invalid_argument("hullMassProperties: minThickness must be > 0");
    std::vector<double> coords;
    Aabb box;
    for (const Vec3& p : points) {
        if (!p.allFinite()) continue;
        box.grow(p);
        coords.insert(coords.end(), {p.x(), p.y(), p.z()});
    }
    if (coords.empty()) throw std::invalid_argument("hullMassProperties: no finite point");

    MassProperties m;
    const Vec3 ref = 0.5 * (box.min + box.max);  // hull coordinates relative to the box centre: better conditioned
    for (std::size_t i = 0; i < coords.size(); i += 3)
        for (int k = 0; k < 3; ++k) coords[i + k] -= ref[k];
    btConvexHullComputer hull;
    hull.compute(coords.data(), 3 * static_cast<int>(sizeof(double)), static_cast<int>(coords.size() / 3), 0, 0);

    // Solid integrals over tetrahedra (hull-vertex mean, face fan): volume, first and second moments.
    double volume = 0;
    Vec3 first = Vec3::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d canonical;
    canonical << 2, 1, 1, 1, 2, 1, 1, 1, 2;
    canonical /= 120.0;
    // The hull's topology comes from Bullet; its vertex positions are Bullet's rounded ones, so the integrals
    // use the original double-precision input points they came from.
    std::vector<Vec3> hullPoints(static_cast<std::size_t>(hull.vertices.size()));
    for (int i = 0; i < hull.vertices.size(); ++i) {
        const int o = i < hull.original_vertex_index.size() ? hull.original_vertex_index[i] : -1;
        const btVector3& p = hull.vertices[i];
        hullPoints[std::size_t(i)] = o >= 0 && 3 * std::size_t(o) + 2 < coords.size()
                                         ? Vec3(coords[3 * std::size_t(o)], coords[3 * std::size_t(o) + 1],
                                                coords[3 * std::size_t(o) + 2])
                                         : Vec3(double(p.x()), double(p.y()), double(p.z()));
    }
    Vec3 apex = Vec3::Zero();
    for (const Vec3& p : hullPoints) apex += p;
    if (!hullPoints.empty()) apex /= double(hullPoints.size());
    auto vertex = [&](int v) -> Vec3 { return hullPoints[std::size_t(v)] - apex; };  // not auto: would dangle
    for (int f = 0; f < hull.faces.size(); ++f) {
        const btConvexHullComputer::Edge* start = &hull.edges[hull.faces[f]];
        const Vec3 v0 = vertex(start->getSourceVertex());
        const btConvexHullComputer::Edge* e = start->getNextEdgeOfFace();
        while (e != start && e->getNextEdgeOfFace() != start) {
            const Vec3 v1 = vertex(e->getSourceVertex());
            const Vec3 v2 = vertex(e->getTargetVertex());
            Eigen::Matrix3d A;
            A.col(0) = v0;
            A.col(1) = v1;
            A.col(2) = v2;
            const double det = A.determinant();
            volume += det / 6.0;
            first += det / 24.0 * (v0 + v1 + v2);
            second += det * A * canonical * A.transpose();
            e = e->getNextEdgeOfFace();
        }
    }
    if (volume < 0) volume = -volume, first = -first, second = -second;  // orientation of the faces

    const Vec3 ext = box.extent().cwiseMax(minThickness);
    const double boxVolume = ext.prod();
    if (!(volume > 1e-3 * boxVolume) || !std::isfinite(volume)) {
        // Flat or degenerate hull: a solid box around the points (at least minThickness thick).
        m.fromHull = false;
        m.volume = boxVolume;
        m.mass = density * boxVolume;
        m.centre = ref;
        m.inertia = Vec3(ext.y() * ext.y() + ext.z() * ext.z(), ext.x() * ext.x() + ext.z() * ext.z(),
                         ext.x() * ext.x() + ext.y() * ext.y()) * (m.mass / 12.0);
        return m;
    }
    const Vec3 c = first / volume;                        // relative to apex
    const Eigen::Matrix3d sc = density * (second - volume * c * c.transpose());  // about the centre of mass
    const Eigen::Matrix3d inertia = sc.trace() * Eigen::Matrix3d::Identity() - sc;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(inertia);
    m.volume = volume;
    m.mass = density * volume;
    m.centre = ref + apex + c;
    m.axes = eig.eigenvectors();
    if (m.axes.determinant() < 0) m.axes.col(2) = -m.axes.col(2);
    // Principal moments, floored so a needle-like piece still has a usable inertia.
    const double floor = 1e-6 * eig.eigenvalues().maxCoeff();
    m.inertia = eig.eigenvalues().cwiseMax(floor);
    return m;
}

}  // namespace cullide::demo
