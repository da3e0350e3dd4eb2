#include "Compare.h"

#include <algorithm>
#include <random>

namespace cullide::test {

std::set<FlatPair> trianglePairs(const Result& result) {
    std::set<FlatPair> out;
    for (const ObjectPair& p : result.pairs)
        for (const TrianglePair& t : p.triangles) out.insert({p.a, t.a, p.b, t.b});
    return out;
}

Comparison runAndCompare(Culler& tested, Culler& reference, const std::vector<Object>& objects, Result& got) {
    Result expected;
    tested.run(objects, got);
    reference.run(objects, expected);
    return compare(expected, got);
}

Comparison compare(const Result& reference, const Result& result) {
    const auto expected = trianglePairs(reference);
    const auto got = trianglePairs(result);
    Comparison c;
    c.expected = expected.size();
    // A reference pair counts as found only if the result names it and its triangles are in the result's
    // triangle-level PCS (what snapshots and users of pcsTriangles see).
    auto inPcs = [&](std::uint32_t object, std::uint32_t triangle) {
        if (object >= result.pcsTriangles.size()) return false;
        const auto& list = result.pcsTriangles[object];
        return std::binary_search(list.begin(), list.end(), triangle);
    };
    for (const auto& p : expected) {
        if (got.count(p) && inPcs(p[0], p[1]) && inPcs(p[2], p[3])) continue;
        if (c.missed++ == 0)
            c.firstMissed = "object " + std::to_string(p[0]) + " tri " + std::to_string(p[1]) + " vs object " +
                            std::to_string(p[2]) + " tri " + std::to_string(p[3]);
    }
    for (const auto& p : got) c.spurious += expected.count(p) ? 0 : 1;
    // Object pairs and the PCS are a function of the input too (reliable mode): they must match exactly.
    auto objectPairs = [](const Result& r) {
        std::vector<std::array<std::uint32_t, 3>> out;
        for (const ObjectPair& p : r.pairs) out.push_back({p.a, p.b, p.hasTriangles ? 1u : 0u});
        return out;
    };
    c.objectPairsEqual = objectPairs(reference) == objectPairs(result) && reference.pcs == result.pcs;
    return c;
}

std::vector<TriangleMesh> randomSoups(std::uint64_t seed, int objects, int trianglesPerObject, double clusterSize) {
    std::mt19937_64 rng(seed);
    auto uniform = [&](double lo, double hi) {
        return lo + (hi - lo) * static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
    };
    std::vector<TriangleMesh> meshes(static_cast<std::size_t>(objects));
    for (auto& m : meshes) {
        const Vec3 centre(uniform(0, 1), uniform(0, 1), uniform(0, 1));
        const double size = clusterSize * uniform(0.3, 1.0);
        for (int t = 0; t < trianglesPerObject; ++t) {
            const Vec3 c = centre + Vec3(uniform(-size, size), uniform(-size, size), uniform(-size, size));
            const double s = size * uniform(0.02, 0.3);
            const auto base = static_cast<std::uint32_t>(m.vertices.size());
            for (int k = 0; k < 3; ++k) m.vertices.push_back(c + Vec3(uniform(-s, s), uniform(-s, s), uniform(-s, s)));
            if (t % 17 == 5) m.vertices.back() = m.vertices[base];  // degenerate: repeated vertex
            if (t % 23 == 7) m.vertices.back() = 0.5 * (m.vertices[base] + m.vertices[base + 1]);  // collinear
            m.triangles.push_back({base, base + 1, base + 2});
        }
    }
    return meshes;
}

std::vector<Object> asObjects(const std::vector<TriangleMesh>& meshes) {
    std::vector<Object> objects(meshes.size());
    for (std::size_t i = 0; i < meshes.size(); ++i) objects[i].mesh = &meshes[i];
    return objects;
}

}  // namespace cullide::test
