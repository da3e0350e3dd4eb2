#include "PairAssembly.h"

#include "exact/CandidateTest.h"

#include <algorithm>
#include <utility>

namespace cullide {

void PairAssembly::decideDevicePairs(const FrameState& frame, const Settings& settings, TaskPool& pool, Stats& stats) {
    m_device = frame.devicePairs;
    std::sort(m_device.begin(), m_device.end());
    m_deviceKeep.assign(m_device.size(), 0);
    std::vector<std::uint8_t> tested(m_device.size(), 0);
    // A certified pair intersects, so its double boxes overlap too: the CPU's exact stage would keep it. Every other
    // pair is a candidate of the CPU's exact stage where its double boxes overlap, and its predicate decides it.
    pool.parallelFor(m_device.size(), 256, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const DevicePair& p = m_device[i];
            if (p.certified) {
                m_deviceKeep[i] = 1;
                continue;
            }
            if (!(*frame.boxesOf[p.a])[p.triangleA].overlaps((*frame.boxesOf[p.b])[p.triangleB])) continue;
            tested[i] = 1;
            if (!settings.exactTriangles) {
                m_deviceKeep[i] = 1;
                continue;
            }
            const TriangleMesh& ma = frame.meshOf(p.a);
            const TriangleMesh& mb = frame.meshOf(p.b);
            const auto& ta = ma.triangles[p.triangleA];
            const auto& tb = mb.triangles[p.triangleB];
            m_deviceKeep[i] = candidateWithin(ma.vertices[ta[0]], ma.vertices[ta[1]], ma.vertices[ta[2]],
                                              mb.vertices[tb[0]], mb.vertices[tb[1]], mb.vertices[tb[2]],
                                              settings.margin)
                                  ? 1
                                  : 0;
        }
    });
    const auto count = [](const std::vector<std::uint8_t>& v) {
        return static_cast<std::size_t>(std::count(v.begin(), v.end(), 1));
    };
    const std::size_t candidates = count(tested);
    const auto certified = static_cast<std::size_t>(
        std::count_if(m_device.begin(), m_device.end(), [](const DevicePair& p) { return p.certified; }));
    stats.candidateTrianglePairs += candidates + certified;
    if (settings.exactTriangles) {
        stats.exactTests += candidates;
        stats.intersectingTrianglePairs += count(m_deviceKeep);
    }
}

void PairAssembly::run(const FrameState& frame, const Settings& settings, ExactStage& exact, Result& result) {
    std::vector<ExactJob> jobs;
    std::vector<std::size_t> jobPair;
    std::vector<BoxJob> boxJobs;
    std::vector<std::size_t> boxJobPair;
    std::vector<std::size_t> devicePairIndex;  // the result pairs whose candidates the device found
    for (const auto& [a, b] : frame.pairs) {
        ObjectPair pair;
        pair.a = a;
        pair.b = b;
        if (frame.isMesh(a) && frame.isMesh(b) && frame.pairsOnDevice(a)) {
            pair.hasTriangles = true;
            devicePairIndex.push_back(result.pairs.size());
        } else if (frame.isMesh(a) && frame.isMesh(b)) {
            // A mesh with a whole tree has no survivors yet (MeshTrees::listPairedTriangles): its tree decides.
            auto none = [&](std::uint32_t o) { return !frame.hasWholeTree(o) && frame.surviving[o].empty(); };
            if (none(a) || none(b)) continue;
            pair.hasTriangles = true;
            jobs.push_back({a, b, &frame.surviving[a], &frame.surviving[b], frame.boxesOf[a], frame.boxesOf[b],
                            frame.order[a], frame.order[b], frame.tree[a], frame.tree[b]});
            jobPair.push_back(result.pairs.size());
        } else if (frame.isMesh(a) || frame.isMesh(b)) {
            const std::uint32_t mesh = frame.isMesh(a) ? a : b;
            const Aabb& box = frame.valid[frame.isMesh(a) ? b : a].box;
            if (!frame.gpuLevels) {
                // The mesh's surviving triangles include every one whose box overlaps this partner's: its tree
                // answers in O(log n) (a landscape under hundreds of bodies).
                boxJobs.push_back(
                    {&frame.surviving[mesh], frame.boxesOf[mesh], box, frame.order[mesh], frame.tree[mesh]});
                boxJobPair.push_back(result.pairs.size());
            } else if (!meshTouchesBox(frame.meshOf(mesh), box, settings.margin)) {  // the levels prune survivors
                continue;
            }
        }
        result.pairs.push_back(std::move(pair));
    }
    exact.run(*frame.objects, jobs, settings.margin, settings.exactTriangles, m_jobResults, result.stats, boxJobs,
              &m_touches, &frame.runDeadline);
    std::vector<std::uint8_t> keep(result.pairs.size(), 1);
    for (std::size_t j = 0; j < boxJobs.size(); ++j) keep[boxJobPair[j]] = m_touches[j];
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        result.pairs[jobPair[j]].triangles = std::move(m_jobResults[j].triangles);
        keep[jobPair[j]] = !result.pairs[jobPair[j]].triangles.empty();
    }
    if (!devicePairIndex.empty()) {
        decideDevicePairs(frame, settings, exact.pool(), result.stats);
        std::size_t at = 0;  // m_device and the pairs are both sorted by object pair
        for (std::size_t i : devicePairIndex) {
            ObjectPair& pair = result.pairs[i];
            const auto before = [&](const DevicePair& p) { return p.a != pair.a ? p.a < pair.a : p.b < pair.b; };
            while (at < m_device.size() && before(m_device[at])) ++at;
            for (; at < m_device.size() && m_device[at].a == pair.a && m_device[at].b == pair.b; ++at)
                if (m_deviceKeep[at]) pair.triangles.push_back({m_device[at].triangleA, m_device[at].triangleB});
            keep[i] = !pair.triangles.empty();
        }
    }
    std::size_t out = 0;
    for (std::size_t i = 0; i < result.pairs.size(); ++i) {
        if (!keep[i]) continue;
        if (out != i) result.pairs[out] = std::move(result.pairs[i]);
        ++out;
    }
    result.pairs.resize(out);
    std::vector<std::uint8_t> inPcs(frame.valid.size(), 0);
    for (const ObjectPair& p : result.pairs) inPcs[p.a] = inPcs[p.b] = 1;
    for (std::uint32_t o = 0; o < inPcs.size(); ++o)
        if (inPcs[o]) result.pcs.push_back(o);
}

}  // namespace cullide
