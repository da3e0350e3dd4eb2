#include "ExactStage.h"

#include "FrameObjects.h"
#include "KeptCapacity.h"
#include "PoolOrHere.h"
#include "exact/BoxTree.h"
#include "exact/CandidateTest.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <utility>

namespace cullide {
struct ExactStage::Scratch {
    std::vector<BoxTree> trees;  ///< one per distinct surviving-triangle list without a ready tree
    std::vector<const BoxTree*> treeOf;  ///< per input: its tree
    std::vector<std::vector<BoxTree::NodePair>> frontiers;  ///< per job
    std::vector<std::vector<TrianglePair>> taskOut;
    std::vector<std::vector<TrianglePair>> groupOut;  ///< per group of a job's tasks: its hits, merged
    std::vector<std::size_t> taskCandidates;  ///< per task: its candidates (box-overlapping triangle pairs)
};

namespace {

/// Tasks whose sorted hits are merged together first (on the workers), before a job merges its groups.
constexpr std::size_t kRunsPerGroup = 16;

/// The sorted lists runs[first .. last) merged into `out` (sorted), pairwise: log2(runs) passes over the pairs.
void mergeRuns(const std::vector<std::vector<TrianglePair>>& runs, std::size_t first, std::size_t last,
               std::vector<TrianglePair>& out) {
    thread_local std::vector<std::size_t> bounds;  // run boundaries in `out`
    thread_local std::vector<TrianglePair> merged;
    out.clear();
    bounds.assign(1, 0);
    for (std::size_t t = first; t < last; ++t) {
        if (runs[t].empty()) continue;
        out.insert(out.end(), runs[t].begin(), runs[t].end());
        bounds.push_back(out.size());
    }
    while (bounds.size() > 2) {
        merged.resize(out.size());
        std::size_t kept = 1;
        for (std::size_t i = 0; i + 1 < bounds.size(); i += 2) {
            const auto from = static_cast<std::ptrdiff_t>(bounds[i]);
            const auto mid = static_cast<std::ptrdiff_t>(bounds[i + 1]);
            const auto to = static_cast<std::ptrdiff_t>(i + 2 < bounds.size() ? bounds[i + 2] : bounds[i + 1]);
            std::merge(out.begin() + from, out.begin() + mid, out.begin() + mid, out.begin() + to,
                       merged.begin() + from);
            bounds[kept++] = static_cast<std::size_t>(to);
        }
        bounds.resize(kept);
        out.swap(merged);
    }
}

/// Keeps the pairs of `pairs` (triangles of a, triangles of b) whose triangles are within `margin`, in order.
void keepWithin(const TriangleMesh& a, const TriangleMesh& b, double margin, std::vector<TrianglePair>& pairs) {
    std::size_t kept = 0;
    for (const TrianglePair& p : pairs) {
        const auto& ta = a.triangles[p.a];
        const auto& tb = b.triangles[p.b];
        if (candidateWithin(a.vertices[ta[0]], a.vertices[ta[1]], a.vertices[ta[2]], b.vertices[tb[0]],
                            b.vertices[tb[1]], b.vertices[tb[2]], margin))
            pairs[kept++] = p;
    }
    pairs.resize(kept);
}

}  // namespace

ExactStage::ExactStage(TaskPool& pool) : m_pool(pool), m_scratch(std::make_unique<Scratch>()) {}
ExactStage::~ExactStage() = default;

void ExactStage::buildTrees(const std::vector<TreeInput>& inputs, std::vector<const BoxTree*>& trees, Stats& stats) {
    std::vector<std::size_t> built;  // inputs without a ready tree
    trees.assign(inputs.size(), nullptr);
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        if (inputs[i].ready != nullptr)
            trees[i] = inputs[i].ready;
        else
            built.push_back(i);
    }
    std::vector<BoxTree>& own = m_scratch->trees;
    if (own.size() < built.size()) own.resize(built.size());
    BoxTree::buildMany(
        m_pool, built.size(), [&](std::size_t k) { return inputs[built[k]].list->size(); },
        [&](std::size_t k, TaskPool* pool) {
            const TreeInput& in = inputs[built[k]];
            own[k].build(*in.boxes, *in.list, pool, in.order);
        });
    for (std::size_t k = 0; k < built.size(); ++k) {
        trees[built[k]] = &own[k];
        ++(own[k].followedOrder() ? stats.exactTreesRefit : stats.exactTreesSorted);
    }
}

void ExactStage::run(const std::vector<Object>& objects, const std::vector<ExactJob>& jobs, double margin, bool exact,
                     std::vector<ExactJobResult>& results, Stats& stats, const std::vector<BoxJob>& boxJobs,
                     std::vector<std::uint8_t>* touches, const Deadline* deadline) {
    results.assign(jobs.size(), ExactJobResult{});
    // Phase 1: a box tree over each object's surviving triangles (once, however many pairs the object is in: a
    // landscape under many bodies), the two trees of each job descended together, split into tasks for every worker.
    std::vector<TreeInput> inputs;
    std::vector<std::size_t> jobListA(jobs.size()), jobListB(jobs.size());
    std::unordered_map<const void*, std::size_t> known;  // by ready tree, else by list
    auto listIndex = [&](const TreeInput& in) {
        const void* key = in.ready != nullptr ? static_cast<const void*>(in.ready) : in.list;
        const auto [it, added] = known.emplace(key, inputs.size());
        if (added) inputs.push_back(in);
        return it->second;
    };
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        jobListA[j] = listIndex({jobs[j].trianglesA, jobs[j].boxesA, jobs[j].orderA, jobs[j].treeA});
        jobListB[j] = listIndex({jobs[j].trianglesB, jobs[j].boxesB, jobs[j].orderB, jobs[j].treeB});
    }
    std::vector<std::size_t> boxJobList(boxJobs.size());
    for (std::size_t j = 0; j < boxJobs.size(); ++j)
        boxJobList[j] = listIndex({boxJobs[j].triangles, boxJobs[j].boxes, boxJobs[j].order, boxJobs[j].tree});
    std::vector<const BoxTree*>& treeOf = m_scratch->treeOf;
    buildTrees(inputs, treeOf, stats);
    auto tree = [&](std::size_t input) -> const BoxTree& { return *treeOf[input]; };
    if (touches != nullptr) {
        touches->assign(boxJobs.size(), 0);
        m_pool.parallelFor(boxJobs.size(), 16, [&](std::size_t begin, std::size_t end) {
            thread_local std::vector<BoxTree::NodePair> stack;
            for (std::size_t j = begin; j < end; ++j)
                (*touches)[j] = tree(boxJobList[j]).anyOverlap(boxJobs[j].box, stack) ? 1 : 0;
        });
    }
    // Node pairs per job in proportion to its trees' size, 64 per worker in all: one large pair (a bunny on a
    // dragon) still feeds every worker, and a thousand small pairs are not cut into a thousand tasks each.
    std::size_t totalLeaves = 0;
    for (std::size_t j = 0; j < jobs.size(); ++j) totalLeaves += tree(jobListA[j]).size() + tree(jobListB[j]).size();
    const double perLeaf = 64.0 * m_pool.size() / static_cast<double>(std::max<std::size_t>(1, totalLeaves));
    std::vector<std::vector<BoxTree::NodePair>>& frontiers = m_scratch->frontiers;
    std::vector<BoxTree::SplitJob> splits(jobs.size());
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        const BoxTree& a = tree(jobListA[j]);
        const BoxTree& b = tree(jobListB[j]);
        splits[j] = {&a, &b, static_cast<std::size_t>(std::ceil(perLeaf * static_cast<double>(a.size() + b.size())))};
    }
    BoxTree::splitMany(splits, &m_pool, frontiers);
    constexpr std::size_t kChunk = 16;  // node pairs per task
    std::vector<std::pair<std::size_t, std::size_t>> tasks;  // (job, first node pair)
    for (std::size_t j = 0; j < jobs.size(); ++j)
        for (std::size_t i = 0; i < frontiers[j].size(); i += kChunk) tasks.emplace_back(j, i);
    std::vector<std::size_t> jobTasks(jobs.size() + 1, tasks.size());  // first task of each job (consecutive)
    for (std::size_t t = tasks.size(); t-- > 0;) jobTasks[tasks[t].first] = t;
    for (std::size_t j = jobs.size(); j-- > 0;) jobTasks[j] = std::min(jobTasks[j], jobTasks[j + 1]);
    auto onlyTask = [&](std::size_t j) { return jobTasks[j + 1] - jobTasks[j] == 1; };
    // Phase 2: each task descends its node pairs and tests its candidates at once (they are still in cache), keeping
    // its hits, sorted; a job's only task keeps them as the job's result.
    std::vector<std::vector<TrianglePair>>& taskOut = m_scratch->taskOut;
    if (taskOut.size() < tasks.size()) taskOut.resize(tasks.size());
    std::vector<std::size_t>& taskCandidates = m_scratch->taskCandidates;
    taskCandidates.assign(tasks.size(), 0);
    m_pool.parallelFor(tasks.size(), 1, [&](std::size_t begin, std::size_t end) {
        // Working memory per thread: vectors of neighbouring tasks share cache lines, and a descent pushes and
        // pops millions of times a frame.
        thread_local std::vector<BoxTree::NodePair> stack;
        thread_local std::vector<TrianglePair> pairs;
        for (std::size_t t = begin; t < end; ++t) {
            const std::size_t j = tasks[t].first;
            const std::vector<BoxTree::NodePair>& frontier = frontiers[j];
            pairs.clear();
            if (deadline != nullptr && deadline->expired()) {  // the run is abandoned: its results are not read
                assignKeeping(onlyTask(j) ? results[j].triangles : taskOut[t], pairs.begin(), pairs.end());
                continue;
            }
            for (std::size_t i = tasks[t].second, last = std::min(frontier.size(), i + kChunk); i < last; ++i)
                BoxTree::leafPairs(tree(jobListA[j]), tree(jobListB[j]), frontier[i], stack, pairs);
            taskCandidates[t] = pairs.size();
            if (exact) keepWithin(*objects[jobs[j].a].mesh, *objects[jobs[j].b].mesh, margin, pairs);
            std::sort(pairs.begin(), pairs.end());
            assignKeeping(onlyTask(j) ? results[j].triangles : taskOut[t], pairs.begin(), pairs.end());
        }
    });
    // Phase 3, for the jobs of several tasks: each group of a job's consecutive tasks merges its tasks' runs, on the
    // workers; then each job of several groups merges its groups' runs (one large pair has hundreds of tasks: its
    // results are neither gathered and sorted nor merged in many passes on one thread).
    std::vector<std::size_t> groupFirst, groupEnd;  // each group's tasks
    std::vector<std::size_t> jobGroups(jobs.size() + 1, 0);  // first group of each job, then the end
    std::size_t total = 0;
    bool severalGroups = false;
    for (std::size_t j = 0; j < jobs.size(); ++j) {
        for (std::size_t t = jobTasks[j]; t < jobTasks[j + 1]; ++t) results[j].candidates += taskCandidates[t];
        total += results[j].candidates;
        jobGroups[j] = groupFirst.size();
        for (std::size_t t = jobTasks[j]; t < jobTasks[j + 1] && !onlyTask(j); t += kRunsPerGroup) {
            groupFirst.push_back(t);
            groupEnd.push_back(std::min(jobTasks[j + 1], t + kRunsPerGroup));
        }
        severalGroups = severalGroups || groupFirst.size() - jobGroups[j] > 1;
    }
    jobGroups[jobs.size()] = groupFirst.size();
    const std::size_t groups = groupFirst.size();
    std::vector<std::vector<TrianglePair>>& groupOut = m_scratch->groupOut;
    if (groupOut.size() < groups) groupOut.resize(groups);
    m_pool.parallelFor(groups, chunkFor(&m_pool, groups, 1, 4), [&](std::size_t begin, std::size_t end) {
        for (std::size_t g = begin; g < end; ++g) {
            // A job's only group merges straight into the job's result.
            const std::size_t j = tasks[groupFirst[g]].first;
            const bool only = jobGroups[j + 1] - jobGroups[j] == 1;
            mergeRuns(taskOut, groupFirst[g], groupEnd[g], only ? results[j].triangles : groupOut[g]);
        }
    });
    if (severalGroups) {
        m_pool.parallelFor(jobs.size(), chunkFor(&m_pool, jobs.size(), 1, 16), [&](std::size_t begin, std::size_t end) {
            for (std::size_t j = begin; j < end; ++j)
                if (jobGroups[j + 1] - jobGroups[j] > 1)
                    mergeRuns(groupOut, jobGroups[j], jobGroups[j + 1], results[j].triangles);
        });
    }
    if (exact)
        for (const ExactJobResult& r : results) stats.intersectingTrianglePairs += r.triangles.size();
    stats.candidateTrianglePairs += total;
    if (exact) stats.exactTests += total;
}

}  // namespace cullide
