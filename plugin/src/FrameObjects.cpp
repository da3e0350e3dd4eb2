#include "FrameObjects.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

namespace cullide {

namespace {

/// A mesh's first defect in one range of its triangles.
struct RangeCheck {
    std::uint32_t object = 0;
    std::size_t begin = 0;
    std::size_t end = 0;
    Aabb box;
    std::size_t badTriangle = SIZE_MAX;  ///< first defective triangle of the range (SIZE_MAX: none)
    std::uint32_t badIndex = 0;
    bool indexOutOfRange = false;
};

void checkRange(const TriangleMesh& m, RangeCheck& r) {
    const std::size_t vertexCount = m.vertices.size();
    double lo[3] = {r.box.min[0], r.box.min[1], r.box.min[2]};
    double hi[3] = {r.box.max[0], r.box.max[1], r.box.max[2]};
    for (std::size_t t = r.begin; t < r.end; ++t) {
        for (std::uint32_t index : m.triangles[t]) {
            if (index >= vertexCount) {
                r.badTriangle = t;
                r.badIndex = index;
                r.indexOutOfRange = true;
                return;
            }
            const Vec3& p = m.vertices[index];
            if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
                r.badTriangle = t;
                r.badIndex = index;
                return;
            }
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min(lo[k], p[k]);
                hi[k] = std::max(hi[k], p[k]);
            }
        }
    }
    r.box.min = Vec3(lo[0], lo[1], lo[2]);
    r.box.max = Vec3(hi[0], hi[1], hi[2]);
}

}  // namespace

std::vector<ValidatedObject> validateObjects(const std::vector<Object>& objects, double margin,
                                             std::vector<ObjectDiagnostic>& rejected, TaskPool* pool,
                                             const std::vector<std::uint8_t>* known) {
    auto isKnown = [&](std::size_t i) { return known != nullptr && (*known)[i] != 0; };
    std::vector<ValidatedObject> out(objects.size());
    // Meshes are checked in ranges of triangles, on every worker when a pool is given.
    constexpr std::size_t kRange = 16384;
    std::vector<RangeCheck> ranges;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        if (objects[i].mesh == nullptr || isKnown(i)) continue;
        const std::size_t n = objects[i].mesh->triangles.size();
        for (std::size_t first = 0; first < n; first += kRange) {
            RangeCheck r;
            r.object = static_cast<std::uint32_t>(i);
            r.begin = first;
            r.end = std::min(n, first + kRange);
            ranges.push_back(r);
        }
    }
    auto check = [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) checkRange(*objects[ranges[k].object].mesh, ranges[k]);
    };
    if (pool != nullptr)
        pool->parallelFor(ranges.size(), 1, check);
    else
        check(0, ranges.size());

    std::size_t next = 0;  // ranges are in object order
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Object& o = objects[i];
        const auto id = static_cast<std::uint32_t>(i);
        ValidatedObject& v = out[i];
        if (isKnown(i)) continue;
        if (o.mesh == nullptr) {
            if (!o.box.isFinite()) {
                rejected.push_back({id, "box proxy has a non-finite coordinate"});
                continue;
            }
            if (o.box.isEmpty()) {
                rejected.push_back({id, "box proxy is empty (min > max)"});
                continue;
            }
            v.valid = true;
            v.box = o.box.inflated(0.5 * margin);
            continue;
        }
        const TriangleMesh& m = *o.mesh;
        std::string error;
        for (; next < ranges.size() && ranges[next].object == id; ++next) {
            const RangeCheck& r = ranges[next];
            if (!error.empty()) continue;
            if (r.badTriangle != SIZE_MAX) {
                if (r.indexOutOfRange)
                    error = "triangle " + std::to_string(r.badTriangle) + " has vertex index " +
                            std::to_string(r.badIndex) + " out of range (" + std::to_string(m.vertices.size()) +
                            " vertices)";
                else
                    error = "vertex " + std::to_string(r.badIndex) + " (triangle " + std::to_string(r.badTriangle) +
                            ") has a non-finite coordinate";
                continue;
            }
            v.box.grow(r.box);
        }
        if (!error.empty()) {
            rejected.push_back({id, error});
            v.box = Aabb{};
            continue;
        }
        if (m.vertices.size() > 0xFFFFFFFFull || m.triangles.size() > 0x7FFFFFFFull) {
            rejected.push_back({id, "mesh too large (more than 2^31 triangles or 2^32 vertices)"});
            continue;
        }
        v.valid = true;
        v.isMesh = true;
        if (!v.box.isEmpty()) v.box = v.box.inflated(0.5 * margin);
    }
    return out;
}

bool meshTouchesBox(const TriangleMesh& mesh, const Aabb& box, double margin) {
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
        if (triangleBounds(mesh, t).inflated(0.5 * margin).overlaps(box)) return true;
    return false;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> overlappingPairs(const std::vector<ValidatedObject>& objects) {
    std::vector<std::uint32_t> order;
    Aabb all;
    for (std::uint32_t i = 0; i < objects.size(); ++i) {
        if (objects[i].valid && !objects[i].box.isEmpty()) {
            order.push_back(i);
            all.grow(objects[i].box);
        }
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    if (order.size() < 2) return pairs;
    int axis = 0;
    all.extent().maxCoeff(&axis);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const double ka = objects[a].box.min[axis];
        const double kb = objects[b].box.min[axis];
        return ka != kb ? ka < kb : a < b;
    });
    for (std::size_t i = 0; i < order.size(); ++i) {
        const Aabb& bi = objects[order[i]].box;
        for (std::size_t j = i + 1; j < order.size(); ++j) {
            const Aabb& bj = objects[order[j]].box;
            if (bj.min[axis] > bi.max[axis]) break;
            if (bi.overlaps(bj)) pairs.emplace_back(std::min(order[i], order[j]), std::max(order[i], order[j]));
        }
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

}  // namespace cullide
