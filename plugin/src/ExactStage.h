// The exact stage: for each potentially colliding mesh pair, candidate triangle pairs by descending box trees over
// the two objects' surviving triangles together, then the robust triangle test, on worker threads.
#pragma once

#include "TaskPool.h"
#include "cullide/Object.h"
#include "cullide/Result.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace cullide {

struct ExactJob {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    const std::vector<std::uint32_t>* trianglesA = nullptr;  ///< surviving triangles of object a
    const std::vector<std::uint32_t>* trianglesB = nullptr;
    const std::vector<Aabb>* boxesA = nullptr;  ///< box of every triangle of object a (inflated by margin / 2)
    const std::vector<Aabb>* boxesB = nullptr;
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

    /// With `exact` false, every candidate is reported (no triangle test).
    void run(const std::vector<Object>& objects, const std::vector<ExactJob>& jobs, double margin, bool exact,
             std::vector<ExactJobResult>& results, Stats& stats);

private:
    struct Scratch;  ///< per-frame working memory, kept between frames: no allocation churn on large scenes
    TaskPool& m_pool;
    std::vector<std::vector<TrianglePair>> m_candidates;
    std::unique_ptr<Scratch> m_scratch;
};

}  // namespace cullide
