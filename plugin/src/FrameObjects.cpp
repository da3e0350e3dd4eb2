#include "FrameObjects.h"

#include <algorithm>
#include <numeric>
#include <string>

namespace cullide {

std::vector<ValidatedObject> validateObjects(const std::vector<Object>& objects, double margin,
                                             std::vector<ObjectDiagnostic>& rejected) {
    std::vector<ValidatedObject> out(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Object& o = objects[i];
        const auto id = static_cast<std::uint32_t>(i);
        ValidatedObject& v = out[i];
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
        const std::size_t vertexCount = m.vertices.size();
        std::string error;
        for (std::size_t t = 0; t < m.triangles.size() && error.empty(); ++t) {
            for (std::uint32_t index : m.triangles[t]) {
                if (index >= vertexCount) {
                    error = "triangle " + std::to_string(t) + " has vertex index " + std::to_string(index) +
                            " out of range (" + std::to_string(vertexCount) + " vertices)";
                    break;
                }
                const Vec3& p = m.vertices[index];
                if (!p.allFinite()) {
                    error = "vertex " + std::to_string(index) + " (triangle " + std::to_string(t) +
                            ") has a non-finite coordinate";
                    break;
                }
                v.box.grow(p);
            }
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
