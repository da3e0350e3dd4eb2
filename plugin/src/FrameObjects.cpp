#include "FrameObjects.h"

#include "PoolOrHere.h"
#include "WorldMeshes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>

namespace cullide {

namespace {

/// One range of a mesh's vertices (finite? their box) or triangles (largest index), checked on a worker.
struct MeshRange {
    std::uint32_t object = 0;
    bool vertices = false;
    std::size_t begin = 0;
    std::size_t end = 0;
    Aabb box;                   ///< vertices: their box
    bool finite = true;         ///< vertices: all finite
    std::uint32_t maxIndex = 0;  ///< triangles: largest vertex index
};

void checkVertices(const TriangleMesh& m, MeshRange& r) {
    // Branch-free: x - x is 0 for finite x and NaN for infinities and NaNs, so a sum is finite iff all are. Two
    // vertices a step, each with its own sums and bounds per axis: one running sum over every coordinate was a chain
    // of dependent additions, three of them per vertex (validation was 6 % of env3's one-thread frame).
    double lo[2][3], hi[2][3], sum[2][3] = {};
    for (int k = 0; k < 3; ++k) {
        lo[0][k] = lo[1][k] = r.box.min[k];
        hi[0][k] = hi[1][k] = r.box.max[k];
    }
    const Vec3* vertices = m.vertices.data();
    std::size_t i = r.begin;
    for (; i + 2 <= r.end; i += 2) {
        for (int j = 0; j < 2; ++j) {
            const Vec3& p = vertices[i + static_cast<std::size_t>(j)];
            for (int k = 0; k < 3; ++k) {
                sum[j][k] += p[k] - p[k];
                lo[j][k] = std::min(lo[j][k], p[k]);
                hi[j][k] = std::max(hi[j][k], p[k]);
            }
        }
    }
    for (; i < r.end; ++i) {
        const Vec3& p = vertices[i];
        for (int k = 0; k < 3; ++k) {
            sum[0][k] += p[k] - p[k];
            lo[0][k] = std::min(lo[0][k], p[k]);
            hi[0][k] = std::max(hi[0][k], p[k]);
        }
    }
    double total = 0.0;
    for (int k = 0; k < 3; ++k) {
        total += sum[0][k] + sum[1][k];
        r.box.min[k] = std::min(lo[0][k], lo[1][k]);
        r.box.max[k] = std::max(hi[0][k], hi[1][k]);
    }
    r.finite = total == 0.0;
}

void checkIndices(const TriangleMesh& m, MeshRange& r) {
    std::uint32_t largest = 0;
    for (std::size_t t = r.begin; t < r.end; ++t)
        for (std::uint32_t index : m.triangles[t]) largest = std::max(largest, index);
    r.maxIndex = largest;
}

/// The slow path, for a mesh with a bad index or a non-finite vertex: its first defect in triangle order (an
/// empty string when only unreferenced vertices are non-finite) and the box of the vertices its triangles use.
std::string firstDefect(const TriangleMesh& m, Aabb& box) {
    const std::size_t vertexCount = m.vertices.size();
    box = Aabb{};
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        for (std::uint32_t index : m.triangles[t]) {
            if (index >= vertexCount)
                return "triangle " + std::to_string(t) + " has vertex index " + std::to_string(index) +
                       " out of range (" + std::to_string(vertexCount) + " vertices)";
            const Vec3& p = m.vertices[index];
            if (!p.allFinite())
                return "vertex " + std::to_string(index) + " (triangle " + std::to_string(t) +
                       ") has a non-finite coordinate";
            box.grow(p);
        }
    }
    return {};
}

}  // namespace

std::vector<ValidatedObject> validateObjects(const std::vector<Object>& objects, double margin,
                                             std::vector<ObjectDiagnostic>& rejected, TaskPool* pool,
                                             const std::vector<std::uint8_t>* known) {
    auto isKnown = [&](std::size_t i) { return known != nullptr && (*known)[i] != 0; };
    std::vector<ValidatedObject> out(objects.size());
    // Fast path, in ranges on every worker when a pool is given: are all vertices finite, all indices in range?
    // Then the box is that of all vertices (a superset of the used ones when some are unused: only looser
    // culling). Otherwise the mesh takes the slow path, in triangle order.
    std::size_t elements = 0;
    for (std::size_t i = 0; i < objects.size(); ++i)
        if (objects[i].mesh != nullptr && !isKnown(i))
            elements += objects[i].mesh->vertices.size() + objects[i].mesh->triangles.size();
    const std::size_t range = chunkFor(pool, elements, 4096, 32768);
    std::vector<MeshRange> ranges;
    for (std::size_t i = 0; i < objects.size(); ++i) {
        if (objects[i].mesh == nullptr || isKnown(i)) continue;
        const TriangleMesh& m = *objects[i].mesh;
        if (m.triangles.empty()) continue;
        for (const bool vertices : {true, false}) {
            const std::size_t n = vertices ? m.vertices.size() : m.triangles.size();
            for (std::size_t first = 0; first < n; first += range) {
                MeshRange r;
                r.object = static_cast<std::uint32_t>(i);
                r.vertices = vertices;
                r.begin = first;
                r.end = std::min(n, first + range);
                ranges.push_back(r);
            }
        }
    }
    auto check = [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            MeshRange& r = ranges[k];
            if (r.vertices)
                checkVertices(*objects[r.object].mesh, r);
            else
                checkIndices(*objects[r.object].mesh, r);
        }
    };
    parallelForOrHere(pool, ranges.size(), 1, check);

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
        bool fast = true;
        for (; next < ranges.size() && ranges[next].object == id; ++next) {
            const MeshRange& r = ranges[next];
            if (r.vertices) {
                fast = fast && r.finite;
                v.box.grow(r.box);
            } else {
                fast = fast && r.maxIndex < m.vertices.size();
            }
        }
        if (!fast) {
            const std::string error = firstDefect(m, v.box);
            if (!error.empty()) {
                rejected.push_back({id, error});
                v.box = Aabb{};
                continue;
            }
        }
        if (m.vertices.size() > 0xFFFFFFFFull || m.triangles.size() > 0x7FFFFFFFull) {
            rejected.push_back({id, "mesh too large (more than 2^31 triangles or 2^32 vertices)"});
            v.box = Aabb{};
            continue;
        }
        if (o.transform != nullptr) {
            // The local box becomes the world box of its transformed corners (rounding included); the vertices
            // themselves are mapped later, only for the objects the pre-pass keeps (WorldMeshes).
            v.localChecked = true;
            v.localBox = v.box;
            if (const char* error = placeTransformed(*o.transform, margin, v)) rejected.push_back({id, error});
            continue;
        }
        v.valid = true;
        v.isMesh = true;
        if (!v.box.isEmpty()) v.box = v.box.inflated(0.5 * margin);
    }
    return out;
}

const char* placeTransformed(const Transform& t, double margin, ValidatedObject& v) {
    const char* error = !isFinite(t) ? "transform has a non-finite coefficient" : nullptr;
    Aabb box;
    if (error == nullptr) {
        box = transformedBounds(t, v.localBox);
        if (!box.isEmpty() && !box.isFinite()) error = "transform maps the mesh beyond the double range";
    }
    v.valid = error == nullptr;
    v.isMesh = v.valid;
    v.box = error != nullptr || box.isEmpty() ? Aabb{} : box.inflated(0.5 * margin);
    return error;
}

bool meshTouchesBox(const TriangleMesh& mesh, const Aabb& box, double margin) {
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
        if (triangleBounds(mesh, t, 0.5 * margin).overlaps(box)) return true;
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

void checkPairList(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& only, std::size_t objectCount) {
    for (std::size_t i = 0; i < only.size(); ++i) {
        const auto [a, b] = only[i];
        if (a >= b || b >= objectCount || (i > 0 && !(only[i - 1] < only[i]))) {
            throw std::invalid_argument("cullide::Culler::run: pair list entry " + std::to_string(i) + " (" +
                                        std::to_string(a) + ", " + std::to_string(b) + ") of " +
                                        std::to_string(only.size()) + " for " + std::to_string(objectCount) +
                                        " objects: pairs must be sorted, without repeats, first < second < the "
                                        "object count");
        }
    }
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> listedOverlappingPairs(
    const std::vector<ValidatedObject>& objects, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& only) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    for (const auto& [a, b] : only) {
        const ValidatedObject& x = objects[a];
        const ValidatedObject& y = objects[b];
        if (x.valid && y.valid && !x.box.isEmpty() && !y.box.isEmpty() && x.box.overlaps(y.box))
            pairs.emplace_back(a, b);
    }
    return pairs;
}

namespace {

std::uint32_t findRoot(std::vector<std::uint32_t>& parent, std::uint32_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];  // path halving
        x = parent[x];
    }
    return x;
}

double largestSide(const Aabb& box) { return box.isEmpty() ? 0.0 : box.extent().maxCoeff(); }

}  // namespace

std::vector<std::vector<std::uint32_t>> clustersOf(const std::vector<std::uint8_t>& member,
                                                   const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
                                                   const std::vector<ValidatedObject>& objects) {
    const auto n = static_cast<std::uint32_t>(objects.size());
    std::vector<std::uint32_t> parent(n);
    for (std::uint32_t i = 0; i < n; ++i) parent[i] = i;
    for (const auto& [a, b] : pairs) {
        if (a >= n || b >= n || !member[a] || !member[b]) continue;
        const std::uint32_t ra = findRoot(parent, a), rb = findRoot(parent, b);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);  // the root is the smallest object
    }
    // Components in the order of their smallest object (their root), with their boxes.
    std::vector<std::vector<std::uint32_t>> components;
    std::vector<Aabb> boxes;
    std::vector<std::uint32_t> componentOf(n, 0);
    for (std::uint32_t i = 0; i < n; ++i) {
        if (!member[i]) continue;
        const std::uint32_t root = findRoot(parent, i);
        if (root == i) {
            componentOf[i] = static_cast<std::uint32_t>(components.size());
            components.emplace_back();
            boxes.emplace_back();
        }
        const std::uint32_t c = componentOf[root];
        components[c].push_back(i);
        boxes[c].grow(objects[i].box);
    }
    // Greedy merge: each component joins the first cluster it stays compact with.
    std::vector<std::vector<std::uint32_t>> clusters;
    std::vector<Aabb> clusterBoxes;
    for (std::size_t c = 0; c < components.size(); ++c) {
        std::size_t into = clusters.size();
        for (std::size_t k = 0; k < clusters.size() && into == clusters.size(); ++k) {
            Aabb merged = clusterBoxes[k];
            merged.grow(boxes[c]);
            if (largestSide(merged) <= kClusterSpread * std::max(largestSide(clusterBoxes[k]), largestSide(boxes[c])))
                into = k;
        }
        if (into == clusters.size()) {
            clusters.emplace_back();
            clusterBoxes.emplace_back();
        }
        clusters[into].insert(clusters[into].end(), components[c].begin(), components[c].end());
        clusterBoxes[into].grow(boxes[c]);
    }
    for (auto& cluster : clusters) std::sort(cluster.begin(), cluster.end());
    return clusters;
}

}  // namespace cullide
