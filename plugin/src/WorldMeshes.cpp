#include "WorldMeshes.h"

#include "KeptCapacity.h"
#include "PoolOrHere.h"

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
    std::vector<std::uint32_t> todo;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        Object& o = m_objects[i];
        if (o.mesh == nullptr || o.transform == nullptr || !needed[i]) {
            if (m_meshes[i].vertices.capacity() != 0) m_meshes[i] = TriangleMesh{};  // bounded memory: release
            continue;
        }
        todo.push_back(static_cast<std::uint32_t>(i));
    }
    auto build = [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::uint32_t i = todo[k];
            const Object& in = objects[i];
            TriangleMesh& world = m_meshes[i];
            resizeKeeping(world.vertices, in.mesh->vertices.size());
            for (std::size_t v = 0; v < world.vertices.size(); ++v)
                world.vertices[v] = transformPoint(*in.transform, in.mesh->vertices[v]);
            world.triangles = in.mesh->triangles;
        }
    };
    parallelForOrHere(pool, todo.size(), 1, build);
    for (const std::uint32_t i : todo) {
        m_objects[i].mesh = &m_meshes[i];
        m_objects[i].transform = nullptr;
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
