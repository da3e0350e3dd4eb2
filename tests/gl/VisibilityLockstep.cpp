#include "VisibilityLockstep.h"

#include "Compare.h"

#include <gtest/gtest.h>

#include <sstream>
#include <utility>

namespace cullide::test {
namespace {

class LockstepBackend final : public PruningBackend {
public:
    LockstepBackend(std::unique_ptr<PruningBackend> tested, std::unique_ptr<PruningBackend> reference,
                    std::shared_ptr<LockstepLog> log)
        : m_tested(std::move(tested)), m_reference(std::move(reference)), m_log(std::move(log)) {}

    void upload(const GpuGeometry& geometry, Stats& stats) override {
        m_tested->upload(geometry, stats);
        m_reference->upload(geometry, m_scratch);
    }
    void forgetUploads() override {
        m_tested->forgetUploads();
        m_reference->forgetUploads();
    }
    std::size_t deviceBytes() const override { return m_tested->deviceBytes(); }
    std::string renderer() const override { return m_tested->renderer(); }
    std::string device() const override { return m_tested->device(); }

    void beginLevel(const LevelItems& items, const View& view, LevelStats& level, Stats& stats) override {
        m_tested->beginLevel(items, view, level, stats);
        m_reference->beginLevel(items, view, m_scratchLevel, m_scratch);
        ++m_log->levels;
        m_iteration = 0;
        m_aliveBefore = items.size();
    }

    IterationResult iterate(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) override {
        const IterationResult got = m_tested->iterate(view, idBits, level, stats);
        const IterationResult expected = m_reference->iterate(view, idBits, m_scratchLevel, m_scratch);
        m_tested->readAlive(m_gotAlive, m_scratchLevel, m_scratch);
        m_reference->readAlive(m_expectedAlive, m_scratchLevel, m_scratch);
        compare(got, expected);
        ++m_iteration;
        return got;
    }

    void readAlive(std::vector<std::uint8_t>& alive, LevelStats& level, Stats& stats) override {
        m_tested->readAlive(alive, level, stats);
    }

private:
    void compare(const IterationResult& got, const IterationResult& expected) {
        LockstepLog& log = *m_log;
        ++log.iterations;
        log.itemsIn += m_aliveBefore;
        log.itemsPruned += m_aliveBefore - got.alive;
        std::size_t differing = 0;
        std::size_t firstDiffering = m_gotAlive.size();
        for (std::size_t i = 0; i < m_gotAlive.size() && i < m_expectedAlive.size(); ++i) {
            if (m_gotAlive[i] == m_expectedAlive[i]) continue;
            if (differing++ == 0) firstDiffering = i;
        }
        const bool countersDiffer = got.overflows != 0 || got.alive != expected.alive ||
                                    (expected.alive != 0 && (got.ownerMin != expected.ownerMin ||
                                                             got.ownerMax != expected.ownerMax ||
                                                             got.bounds.min != expected.bounds.min ||
                                                             got.bounds.max != expected.bounds.max));
        if (differing != 0 || countersDiffer || m_gotAlive.size() != m_expectedAlive.size()) {
            ++log.mismatches;
            log.itemsDiffering += differing;
            if (log.details.size() < 8) {
                std::ostringstream s;
                s << "level " << log.levels << " iteration " << m_iteration << ": " << m_aliveBefore
                  << " items in, GL keeps " << got.alive << " (overflows " << got.overflows << "), reference keeps "
                  << expected.alive << ", " << differing << " items differ";
                if (differing != 0)
                    s << " (first: item " << firstDiffering << ", GL " << int(m_gotAlive[firstDiffering])
                      << ", reference " << int(m_expectedAlive[firstDiffering]) << ")";
                log.details.push_back(s.str());
            }
        }
        m_aliveBefore = got.alive;
    }

    std::unique_ptr<PruningBackend> m_tested;
    std::unique_ptr<PruningBackend> m_reference;
    std::shared_ptr<LockstepLog> m_log;
    Stats m_scratch;  ///< what the checks cost is not the culler's
    LevelStats m_scratchLevel;
    std::size_t m_iteration = 0;
    std::size_t m_aliveBefore = 0;
    std::vector<std::uint8_t> m_gotAlive;
    std::vector<std::uint8_t> m_expectedAlive;
};

}  // namespace

std::string LockstepLog::summary() const {
    std::ostringstream s;
    s << levels << " levels, " << iterations << " iterations, " << itemsIn << " items in, " << itemsPruned
      << " pruned, " << mismatches << " iterations differ (" << itemsDiffering << " items)";
    for (const std::string& d : details) s << "\n  " << d;
    return s.str();
}

PruningBackendFactory lockstepFactory(std::shared_ptr<LockstepLog> log, GlBackendOptions options) {
    return [log, options](const Settings& settings) -> std::unique_ptr<PruningBackend> {
        return std::make_unique<LockstepBackend>(createGlPruningBackend(settings, options),
                                                 createReferencePruningBackend(settings), log);
    };
}

std::string lockstepName(const LockstepCase& c) {
    return std::string(c.pipeline == Pipeline::Paper ? "Paper" : "Auto") +
           (c.mode == Mode::Reliable ? "Reliable" : "Sampled") + (c.backend == Backend::Raster ? "Raster" : "Compute") +
           std::to_string(c.resolution);
}

void PrintTo(const LockstepCase& c, std::ostream* os) { *os << lockstepName(c); }

Settings lockstepSettings(const LockstepCase& c) {
    Settings s;
    s.pipeline = c.pipeline;
    s.mode = c.mode;
    s.backend = c.backend;
    s.resolution = c.resolution;
    s.gpuLevels = GpuLevels::Always;
    s.exactThreshold = 0;  // every level runs
    s.threads = 2;
    return s;
}

LockstepLog runInLockstep(const Settings& settings, const std::vector<std::vector<TriangleMesh>>& frames) {
    auto log = std::make_shared<LockstepLog>();
    std::unique_ptr<Culler> culler = createGpuCuller(settings, lockstepFactory(log));
    for (const std::vector<TriangleMesh>& meshes : frames) {
        Result r;
        culler->run(asObjects(meshes), r);
        EXPECT_EQ(r.stats.gpuFallbacks, 0u) << r.stats.gpuError;
    }
    return *log;
}

}  // namespace cullide::test
