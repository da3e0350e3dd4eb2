#include "PairAssembly.h"

namespace cullide {

void PairAssembly::run(const FrameState& frame, const Settings& settings, ExactStage& exact, Result& result) {
    std::vector<ExactJob> jobs;
    std::vector<std::size_t> jobPair;
    std::vector<BoxJob> boxJobs;
    std::vector<std::size_t> boxJobPair;
    for (const auto& [a, b] : frame.pairs) {
        ObjectPair pair;
        pair.a = a;
        pair.b = b;
        if (frame.isMesh(a) && frame.isMesh(b)) {
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
