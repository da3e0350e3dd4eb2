// The brute-force oracle: every triangle pair of every box-overlapping object pair, exact test.
#include "FrameObjects.h"
#include "cullide/TaskPool.h"
#include "WorldMeshes.h"
#include "cullide/Timer.h"
#include "cullide/Culler.h"
#include "cullide/TriangleTest.h"

#include <algorithm>
#include <stdexcept>

namespace cullide {
namespace {

class ReferenceCuller final : public Culler {
public:
    explicit ReferenceCuller(const Settings& settings) : m_settings(settings), m_pool(settings.threads) {}

    const Settings& settings() const override { return m_settings; }

    void run(const std::vector<Object>& input, Result& result) override { runFrame(input, nullptr, result); }

    void run(const std::vector<Object>& input, const std::vector<ObjectIndexPair>& only, Result& result) override {
        checkPairList(only, input.size());
        runFrame(input, &only, result);
    }

private:
    void runFrame(const std::vector<Object>& input, const std::vector<ObjectIndexPair>* only, Result& result) {
        Timer total;
        result.clear();
        Stats& stats = result.stats;
        stats.renderer = "cpu-reference";
        const double margin = m_settings.margin;
        const auto valid = validateObjects(input, margin, result.rejected);
        stats.objects = input.size();
        stats.rejectedObjects = result.rejected.size();
        const auto pairs = only != nullptr ? listedOverlappingPairs(valid, *only) : overlappingPairs(valid);
        std::vector<std::uint8_t> paired(input.size(), 0);
        for (const auto& [a, b] : pairs) paired[a] = paired[b] = 1;
        const std::vector<Object>& objects = m_world.resolve(input, paired, &m_pool);  // world-space meshes
        std::vector<ObjectPair> out(pairs.size());
        std::vector<std::uint8_t> keep(pairs.size(), 0);
        m_pool.parallelFor(pairs.size(), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                const auto [a, b] = pairs[p];
                ObjectPair& pair = out[p];
                pair.a = a;
                pair.b = b;
                pair.hasTriangles = valid[a].isMesh && valid[b].isMesh;
                if (!pair.hasTriangles) {
                    keep[p] = !valid[a].isMesh && !valid[b].isMesh
                                  ? 1
                                  : meshTouchesBox(*objects[valid[a].isMesh ? a : b].mesh,
                                                   valid[valid[a].isMesh ? b : a].box, margin);
                    continue;
                }
                const TriangleMesh& ma = *objects[a].mesh;
                const TriangleMesh& mb = *objects[b].mesh;
                // All pairs of triangles, except those that cannot reach the other object's (inflated) box.
                std::vector<std::pair<std::uint32_t, Aabb>> boxesB;
                for (std::uint32_t tb = 0; tb < mb.triangles.size(); ++tb) {
                    const Aabb box = triangleBounds(mb, tb).inflated(0.5 * margin);
                    if (box.overlaps(valid[a].box)) boxesB.emplace_back(tb, box);
                }
                for (std::uint32_t ta = 0; ta < ma.triangles.size(); ++ta) {
                    const Aabb boxA = triangleBounds(ma, ta).inflated(0.5 * margin);
                    if (!boxA.overlaps(valid[b].box)) continue;
                    const auto& A = ma.triangles[ta];
                    for (const auto& [tb, boxB] : boxesB) {
                        if (!boxA.overlaps(boxB)) continue;
                        const auto& B = mb.triangles[tb];
                        if (trianglesWithin(ma.vertices[A[0]], ma.vertices[A[1]], ma.vertices[A[2]],
                                            mb.vertices[B[0]], mb.vertices[B[1]], mb.vertices[B[2]], margin))
                            pair.triangles.push_back({ta, tb});
                    }
                }
                keep[p] = !pair.triangles.empty();
            }
        });
        std::vector<std::uint8_t> inPcs(objects.size(), 0);
        result.pcsTriangles.assign(objects.size(), {});
        for (std::size_t p = 0; p < out.size(); ++p) {
            ObjectPair& pair = out[p];
            if (!keep[p]) continue;
            stats.intersectingTrianglePairs += pair.triangles.size();
            inPcs[pair.a] = inPcs[pair.b] = 1;
            for (const TrianglePair& t : pair.triangles) {
                result.pcsTriangles[pair.a].push_back(t.a);
                result.pcsTriangles[pair.b].push_back(t.b);
            }
            result.pairs.push_back(std::move(pair));
        }
        for (std::uint32_t o = 0; o < inPcs.size(); ++o)
            if (inPcs[o]) result.pcs.push_back(o);
        for (auto& list : result.pcsTriangles) {
            std::sort(list.begin(), list.end());
            list.erase(std::unique(list.begin(), list.end()), list.end());
        }
        stats.pcsObjects = result.pcs.size();
        stats.candidateObjectPairs = result.pairs.size();
        stats.totalMs = total.ms();
    }

    Settings m_settings;
    TaskPool m_pool;
    WorldMeshes m_world;
};

}  // namespace

std::unique_ptr<Culler> createReferenceCuller(const Settings& settings) {
    const std::string error = settings.validate();
    if (!error.empty()) throw std::invalid_argument("cullide::Settings: " + error);
    return std::make_unique<ReferenceCuller>(settings);
}

}  // namespace cullide
