// The exact stage: for each potentially colliding mesh pair, candidate triangle pairs by descending box trees over
// the two objects' surviving triangles together, then the robust triangle test, on worker threads.
#pragma once

#include "Deadline.h"
#include "cullide/TaskPool.h"
#include "cullide/Object.h"
#include "cullide/Result.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace cullide {

class BoxTree;

struct ExactJob {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    const std::vector<std::uint32_t>* trianglesA = nullptr;  ///< surviving triangles of object a
    const std::vector<std::uint32_t>* trianglesB = nullptr;
    const std::vector<Aabb>* boxesA = nullptr;  ///< box of every triangle of object a (inflated by margin / 2)
    const std::vector<Aabb>* boxesB = nullptr;
    /// Optional: a spatial order of all of object a's triangles (TriangleOrders), which its box tree may follow.
    const std::vector<std::uint32_t>* orderA = nullptr;
    const std::vector<std::uint32_t>* orderB = nullptr;
    /// Optional: a box tree of all of object a's triangles (MeshTrees), used instead of one over trianglesA (then not
    /// read). Its extra leaves change no pair: their boxes meet no partner's object box, so no partner triangle's.
    const BoxTree* treeA = nullptr;
    const BoxTree* treeB = nullptr;
};

/// A mesh against a box-only proxy: does some surviving triangle's box (inflated by margin / 2) overlap `box`
/// (already inflated by margin / 2)?
struct BoxJob {
    const std::vector<std::uint32_t>* triangles = nullptr;  ///< surviving triangles of the mesh
    const std::vector<Aabb>* boxes = nullptr;               ///< box of every triangle of the mesh
    Aabb box;
    const std::vector<std::uint32_t>* order = nullptr;  ///< optional, as ExactJob::orderA
    const BoxTree* tree = nullptr;                      ///< optional, as ExactJob::treeA
};

struct ExactJobResult {
    std::size_t candidates = 0;          ///< triangle pairs whose boxes (inflated by margin / 2) overlap
    std::vector<TrianglePair> triangles;  ///< intersecting / within-margin pairs (or all candidates), sorted
};

class ExactStage {
public:
    /// Runs on `pool`, which must outlive the stage.
    explicit ExactStage(TaskPool& pool);
    ~ExactStage();
    ExactStage(const ExactStage&) = delete;
    ExactStage& operator=(const ExactStage&) = delete;

    /// The pool it runs on.
    TaskPool& pool() const { return m_pool; }

    /// With `exact` false, every candidate is reported (no triangle test).
    /// Box jobs are answered in `touches` (1: some triangle box overlaps), from the same trees.
    /// Tasks that start once `deadline` (optional) has passed do nothing: the caller, seeing it passed, discards
    /// the results.
    void run(const std::vector<Object>& objects, const std::vector<ExactJob>& jobs, double margin, bool exact,
             std::vector<ExactJobResult>& results, Stats& stats, const std::vector<BoxJob>& boxJobs = {},
             std::vector<std::uint8_t>* touches = nullptr, const Deadline* deadline = nullptr);

private:
    /// What one box tree is built over: a surviving-triangle list, the mesh's triangle boxes, and optionally the
    /// mesh's spatial order; or a tree given ready (then nothing is built).
    struct TreeInput {
        const std::vector<std::uint32_t>* list;
        const std::vector<Aabb>* boxes;
        const std::vector<std::uint32_t>* order;
        const BoxTree* ready;
    };
    /// The tree of each input: its ready one, or one built now into the scratch trees.
    void buildTrees(const std::vector<TreeInput>& inputs, std::vector<const BoxTree*>& trees, Stats& stats);

    struct Scratch;  ///< per-frame working memory, kept between frames: no allocation churn on large scenes
    TaskPool& m_pool;
    std::unique_ptr<Scratch> m_scratch;
};

}  // namespace cullide
