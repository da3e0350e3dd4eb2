#include "WorldMeshes.h"

#include "KeptCapacity.h"
#include "PoolOrHere.h"

#include <algorithm>

namespace cullide {

Vec3 transformPoint(const Transform& t, const Vec3& p) {
    // Written out so that the order of operations is the documented one; the library is compiled with
    // -ffp-contract=off, so no multiply-add is fused whatever the target.
    Vec3 w;
    for (int i = 0; i < 3; ++i) {
        double x = t.linear(i, 0) * p[0];
        x = x + t.linear(i, 1) * p[1];
        x = x + t.linear(i, 2) * p[2];
        w[i] = x + t.translation[i];
    }
    return w;
}

bool isFinite(const Transform& t) { return t.linear.allFinite() && t.translation.allFinite(); }

Aabb transformedBounds(const Transform& t, const Aabb& local) {
    // No rounding bound is needed: transformPoint is monotone in each coordinate of p. Each product l_ik * p_k,
    // rounded, is monotone in p_k (non-decreasing for l_ik >= 0, non-increasing otherwise), and a rounded sum is
    // non-decreasing in both operands, so coordinate i of transformPoint(t, p) over the box is largest at the corner
    // that takes max_k where l_ik >= 0 and min_k elsewhere, and smallest at the opposite corner: the box of the eight
    // transformed corners holds every transformed point of `local`, bit for bit (overflow to infinity included).
    if (local.isEmpty()) return Aabb{};
    Aabb box;
    for (int corner = 0; corner < 8; ++corner) {
        const Vec3 p((corner & 1) ? local.max[0] : local.min[0], (corner & 2) ? local.max[1] : local.min[1],
                     (corner & 4) ? local.max[2] : local.min[2]);
        box.grow(transformPoint(t, p));
    }
    return box;
}

const std::vector<Object>& WorldMeshes::resolve(const std::vector<Object>& objects,
                                                const std::vector<std::uint8_t>& needed, TaskPool* pool) {
    m_objects = objects;
    m_meshes.resize(objects.size());
    // Ranges of vertices, so that one large mesh is mapped on every worker; a mesh's triangles are copied with its
    // first range.
    struct Range {
        std::uint32_t object;
        std::size_t begin;
        std::size_t end;
    };
    std::vector<Range> ranges;
    std::size_t vertices = 0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Object& o = objects[i];
        if (o.mesh != nullptr && o.transform != nullptr && needed[i]) vertices += o.mesh->vertices.size();
    }
    const std::size_t chunk = chunkFor(pool, vertices, 2048, 16384);
    for (std::size_t i = 0; i < objects.size(); ++i) {
        Object& o = m_objects[i];
        if (o.mesh == nullptr || o.transform == nullptr || !needed[i]) {
            if (m_meshes[i].vertices.capacity() != 0) m_meshes[i] = TriangleMesh{};  // bounded memory: release
            continue;
        }
        const std::size_t n = o.mesh->vertices.size();
        resizeKeeping(m_meshes[i].vertices, n);
        for (std::size_t first = 0; first == 0 || first < n; first += chunk)
            ranges.push_back({static_cast<std::uint32_t>(i), first, std::min(n, first + chunk)});
    }
    auto build = [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const Range& r = ranges[k];
            const Object& in = objects[r.object];
            TriangleMesh& world = m_meshes[r.object];
            for (std::size_t v = r.begin; v < r.end; ++v)
                world.vertices[v] = transformPoint(*in.transform, in.mesh->vertices[v]);
            if (r.begin == 0) world.triangles = in.mesh->triangles;
        }
    };
    parallelForOrHere(pool, ranges.size(), 1, build);
    for (const Range& r : ranges) {
        if (r.begin != 0) continue;
        m_objects[r.object].mesh = &m_meshes[r.object];
        m_objects[r.object].transform = nullptr;
    }
    return m_objects;
}

std::size_t WorldMeshes::bytes() const {
    std::size_t total = 0;
    for (const TriangleMesh& m : m_meshes)
        total += m.vertices.capacity() * sizeof(Vec3) + m.triangles.capacity() * sizeof(TriangleIndices);
    return total;
}

}  // namespace cullide
