#include "TriangleOrders.h"

#include "KeptCapacity.h"
#include "Morton.h"
#include "PoolOrHere.h"

#include <algorithm>
#include <utility>

namespace cullide {
namespace {

Vec3 centroid(const TriangleMesh& mesh, std::size_t t) {
    const auto& tri = mesh.triangles[t];
    return (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0;
}

}  // namespace

void spatialOrder(const TriangleMesh& mesh, std::vector<std::uint32_t>& order, TaskPool* pool) {
    thread_local std::vector<std::uint64_t> keys;  // per thread: small meshes are ordered one per worker
    thread_local std::vector<std::uint64_t> tmp;
    thread_local std::vector<std::uint32_t> counts;
    thread_local std::vector<Aabb> chunkBounds;
    const std::size_t n = mesh.triangles.size();
    const std::size_t chunk = chunkFor(pool, n, 4096, 16384);
    const std::size_t chunks = (n + chunk - 1) / chunk;
    assignKeeping(chunkBounds, chunks, Aabb{});
    std::vector<Aabb>& bounds = chunkBounds;  // the caller's, for the workers
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t c = begin; c < end; ++c)
            for (std::size_t t = c * chunk, last = std::min(n, t + chunk); t < last; ++t)
                bounds[c].grow(centroid(mesh, t));
    });
    Aabb all;
    for (const Aabb& b : bounds) all.grow(b);
    const Vec3 scale = (all.extent().array().max(1e-300)).inverse() * 1023.0;
    resizeKeeping(keys, n);
    std::uint64_t* key = keys.data();
    parallelForOrHere(pool, chunks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin * chunk, last = std::min(n, end * chunk); t < last; ++t) {
            const Vec3 c = (centroid(mesh, t) - all.min).cwiseProduct(scale);
            key[t] = morton::key(morton::code(c[0], c[1], c[2]), static_cast<std::uint32_t>(t));
        }
    });
    morton::sortByCode(keys, tmp, counts, pool);
    resizeKeeping(order, n);
    for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(keys[i]);
}

bool TriangleOrders::current(const Entry& e, const Object& object) const {
    const TriangleMesh& mesh = *object.mesh;
    if (!e.ready || e.vertices != mesh.vertices.size() || e.triangles != mesh.triangles.size()) return false;
    if (object.staticKey != 0 && e.staticKey == object.staticKey) return e.version == object.version;
    return m_frame < e.dueFrame;  // unkeyed, or an instance with another key: as an unkeyed mesh
}

void TriangleOrders::beginFrame(std::size_t objectCount, FrameState& frame) {
    ++m_frame;
    for (auto it = m_entries.begin(); it != m_entries.end();)
        it = m_frame - it->second.lastFrame > kKeepFrames ? m_entries.erase(it) : std::next(it);
    frame.order.assign(objectCount, nullptr);
    frame.orderSerial.assign(objectCount, 0);
}

std::size_t TriangleOrders::assign(const std::vector<Object>& objects, FrameState& frame,
                                   const std::function<bool(std::uint32_t)>& wanted, TaskPool& pool) {
    struct Due {
        const TriangleMesh* mesh;
        Entry* entry;
        std::vector<std::uint32_t> order;  ///< computed now
    };
    std::vector<Due> due;  // meshes ordered now, each once
    std::vector<std::pair<std::uint32_t, const Entry*>> assigned;
    for (std::uint32_t o = 0; o < objects.size(); ++o) {
        if (!frame.isActiveMesh(o) || frame.order[o] != nullptr || !wanted(o)) continue;
        const Object& object = objects[o];
        const auto [it, added] = m_entries.try_emplace(object.mesh);
        Entry& e = it->second;
        if (e.lastFrame != m_frame && !current(e, object)) {
            // Spread the recomputations of meshes first seen together over the frames that follow.
            e.dueFrame = m_frame + kRefreshFrames + (added ? m_computed % kRefreshFrames : 0);
            e.vertices = object.mesh->vertices.size();
            e.triangles = object.mesh->triangles.size();
            e.staticKey = object.staticKey;
            e.version = object.version;
            e.ready = false;  // until computed below
            due.push_back({object.mesh, &e, {}});
            ++m_computed;
        }
        e.lastFrame = m_frame;
        frame.order[o] = &e.order;
        assigned.emplace_back(o, &e);
    }
    // The source meshes: a transformed object's world copy has the same triangles, in the same order.
    std::vector<std::size_t> small;
    for (std::size_t i = 0; i < due.size(); ++i) {
        if (due[i].mesh->triangles.size() < kSpreadTriangles)
            small.push_back(i);
        else
            spatialOrder(*due[i].mesh, due[i].order, &pool);
    }
    pool.parallelFor(small.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) spatialOrder(*due[small[i]].mesh, due[small[i]].order);
    });
    for (Due& d : due) {
        // The same permutation again (a refresh of a mesh that did not change) keeps its serial, and what follows it.
        if (d.order != d.entry->order) {
            d.entry->order.swap(d.order);
            d.entry->serial = ++m_serial;
        }
        d.entry->ready = true;
    }
    for (const auto& [o, e] : assigned) frame.orderSerial[o] = e->serial;
    return due.size();
}

}  // namespace cullide
