#include "VisibilityLockstep.h"

#include "Compare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <cstring>
#include <sstream>
#include <utility>

namespace cullide::test {
namespace {

class LockstepBackend final : public PruningBackend {
public:
    LockstepBackend(std::unique_ptr<PruningBackend> tested, std::unique_ptr<PruningBackend> reference,
                    std::shared_ptr<LockstepLog> log, std::shared_ptr<std::vector<float>> devicePositions,
                    std::shared_ptr<std::vector<float>> deviceBoxes)
        : m_tested(std::move(tested)), m_reference(std::move(reference)), m_log(std::move(log)),
          m_devicePositions(std::move(devicePositions)), m_deviceBoxes(std::move(deviceBoxes)) {}

    /// Every upload: the positions the device holds against allPositions, bit for bit (the mapped meshes' are
    /// mapped there by map.comp), and its boxes against allBoxes by value (only what changed is sent; the groups of
    /// meshes that are not static are built there by group_boxes.comp).
    void upload(const GpuGeometry& geometry, Stats& stats) override {
        m_tested->upload(geometry, stats);
        m_reference->upload(geometry, m_scratch);
        const std::vector<float> expected = allPositions(geometry);
        ++m_log->uploads;
        m_log->mappedVertices += expected.size() / 3 - geometry.positions.size() / 3;
        compareFloats(thisUpload(geometry, expected), thisUpload(geometry, *m_devicePositions), "position");
        compareFloats(allBoxes(geometry, expected), *m_deviceBoxes, "box", true);
        m_log->builtBoxes += geometry.builtRanges.size() / 2;
    }
    /// The positions of this upload's meshes: `positions`, then each mapped mesh's (the places between them belong to
    /// meshes of other uploads, which the device still holds).
    static std::vector<float> thisUpload(const GpuGeometry& geometry, const std::vector<float>& all) {
        std::vector<float> kept(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(
                                                               std::min(all.size(), geometry.positions.size())));
        for (const MappedMesh& m : geometry.mapped) {
            const std::size_t first = 3 * std::size_t{m.baseVertex}, end = first + 3 * std::size_t{m.count};
            if (end <= all.size()) kept.insert(kept.end(), all.begin() + first, all.begin() + end);
        }
        return kept;
    }
    /// Bit for bit, or (`byValue`: boxes, whose -0 and +0 nothing tells apart) by value.
    void compareFloats(const std::vector<float>& expected, const std::vector<float>& got, const char* what,
                       bool byValue = false) {
        std::size_t differing = 0;
        for (std::size_t i = 0; i < expected.size() && i < got.size(); ++i) {
            const bool same = byValue ? expected[i] == got[i] : std::memcmp(&expected[i], &got[i], 4) == 0;
            differing += same ? 0 : 1;
        }
        if (differing != 0 || expected.size() != got.size())
            note(0, "upload " + std::to_string(m_log->uploads) + ": " + std::to_string(differing) + " of " +
                        std::to_string(expected.size()) + " " + what + " floats differ on the device");
    }
    void beginFrame() override {
        m_tested->beginFrame();
        m_reference->beginFrame();
        m_deferred.clear();
    }
    void forgetUploads() override {
        m_tested->forgetUploads();
        m_reference->forgetUploads();
    }
    std::size_t deviceBytes() const override { return m_tested->deviceBytes(); }
    std::string renderer() const override { return m_tested->renderer(); }
    std::string device() const override { return m_tested->device(); }
    bool hardwareDevice() const override { return m_tested->hardwareDevice(); }

    void pruneLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                    LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) override {
        m_got.clear();
        m_expected.clear();
        m_scratchLevel = LevelStats{};
        m_scratchLevel.itemsPerIteration.push_back(items.size());  // as startLevel does: the items alive at the start
        m_reference->pruneLevel(items, start, m_expectedAlive, m_scratchLevel, m_scratch, &m_expected);
        try {
            m_tested->pruneLevel(items, start, survivors, level, stats, &m_got);
        } catch (const LevelsRerun&) {
            m_ahead.reset();  // both levels run again
            throw;
        }
        compareAhead(stats);
        ++m_log->levels;
        compare(m_got, m_expected, {startOf(level, items.size()), startOf(m_scratchLevel, items.size())}, &survivors,
                m_expectedAlive);
        if (trace) trace->insert(trace->end(), m_got.begin(), m_got.end());
    }

    /// The tested level's trace is complete once the next level is waited for: compared then (its survivors are
    /// compared through the next level's, which inherit them).
    void pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                         std::vector<IterationTrace>* trace) override {
        m_ahead = std::make_unique<Ahead>();  // the tested trace's address stays valid until a deferred level's collect
        m_ahead->items = items.size();
        m_ahead->levelIndex = levelIndex;
        m_scratch.levels.assign(1, LevelStats{});
        m_scratch.levels[0].itemsPerIteration.push_back(items.size());
        m_reference->pruneLevelAhead(items, start, 0, m_scratch, &m_ahead->expected);
        m_ahead->expectedStart = startOf(m_scratch.levels[0], items.size());
        m_tested->pruneLevelAhead(items, start, levelIndex, stats, &m_ahead->got);
        (void)trace;  // the culler asks for none (the tested trace comes with the next level)
    }

    void settle(Stats& stats) override {
        m_tested->settle(stats);
        compareAhead(stats);
    }

    /// The reference runs the level now, the tested backend defers it: both are compared at collect().
    void pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                            std::vector<IterationTrace>* trace) override {
        auto d = std::make_unique<Deferred>();
        d->items = items.size();
        d->levelIndex = levelIndex;
        m_scratch.levels.assign(1, LevelStats{});
        m_scratch.levels[0].itemsPerIteration.push_back(items.size());
        m_reference->pruneLevelDeferred(items, start, 0, m_scratch, &d->expected);
        std::vector<DeferredLevel> expected;
        m_reference->collect(Deadline(), expected, m_scratch);
        d->expectedAlive = std::move(expected.at(0).survivors);
        d->expectedExact = std::move(expected.at(0).exactPairs);
        d->expectedStart = startOf(m_scratch.levels[0], items.size());
        try {
            m_tested->pruneLevelDeferred(items, start, levelIndex, stats, &d->got);
        } catch (const LevelsRerun&) {
            m_ahead.reset();  // both levels run again
            throw;
        }
        d->ahead = std::move(m_ahead);
        m_deferred.push_back(std::move(d));
        (void)trace;  // the culler asks for none
    }

    /// Each deferred level that ran as one chain (and the level run ahead before it) against the reference: its
    /// trace and its survivors item by item. One that stopped early runs again, waited for, and is compared then.
    bool collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) override {
        std::vector<std::unique_ptr<Deferred>> deferred;
        deferred.swap(m_deferred);
        if (!m_tested->collect(until, results, stats)) return false;
        if (results.size() != deferred.size()) note(0, "collect() returned a result per deferred level");
        for (std::size_t k = 0; k < results.size() && k < deferred.size(); ++k) {
            Deferred& d = *deferred[k];
            ++m_log->levelsDeferred;
            if (!results[k].complete) continue;
            if (d.ahead) compareAheadOf(*d.ahead, stats);
            ++m_log->levels;
            const std::size_t gotStart =
                d.levelIndex < stats.levels.size() ? startOf(stats.levels[d.levelIndex], d.items) : d.items;
            compare(d.got, d.expected, {gotStart, d.expectedStart}, &results[k].survivors, d.expectedAlive);
            if (results[k].exactRan) compareExact(results[k].exactPairs, d.expectedExact);
        }
        return true;
    }

private:
    /// A level run ahead: its traces (the tested one complete after the next level's read-back).
    struct Ahead {
        std::size_t items = 0;
        std::size_t levelIndex = 0;     ///< its stats' place (Stats::levels), complete when compared
        std::size_t expectedStart = 0;  ///< the items alive at its start in the reference
        std::vector<IterationTrace> got;
        std::vector<IterationTrace> expected;
    };
    /// A deferred level: the reference's result, and the tested trace filled at collect().
    struct Deferred {
        std::size_t items = 0;
        std::size_t levelIndex = 0;
        std::size_t expectedStart = 0;
        std::vector<IterationTrace> got;
        std::vector<IterationTrace> expected;
        std::vector<std::uint8_t> expectedAlive;
        std::vector<std::uint32_t> expectedExact;  ///< the reference's exact pairs (DeferredLevel::exactPairs)
        std::unique_ptr<Ahead> ahead;
    };

    /// The device exact stage's pairs and verdicts against the reference's (in any order: the device appends them
    /// as its invocations finish).
    void compareExact(const std::vector<std::uint32_t>& got, const std::vector<std::uint32_t>& expected) {
        auto sorted = [](const std::vector<std::uint32_t>& words) {
            std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
            for (std::size_t w = 0; w + 1 < words.size(); w += 2) pairs.emplace_back(words[w], words[w + 1]);
            std::sort(pairs.begin(), pairs.end());
            return pairs;
        };
        const auto a = sorted(got), b = sorted(expected);
        m_log->exactPairs += a.size();
        for (const auto& p : a) m_log->exactCertified += (p.second & CULLIDE_EXACT_WITHIN) != 0 ? 1 : 0;
        if (a == b) return;
        std::size_t differing = 0;
        std::vector<std::pair<std::uint32_t, std::uint32_t>> diff;
        std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(diff));
        differing = diff.size();
        note(0, "the device exact stage wrote " + std::to_string(a.size()) + " pairs, the reference " +
                    std::to_string(b.size()) + "; " + std::to_string(differing) + " differ (pair or verdict)");
    }

    void compareAhead(const Stats& stats) {
        if (!m_ahead) return;
        const std::unique_ptr<Ahead> ahead = std::move(m_ahead);
        compareAheadOf(*ahead, stats);
    }

    void compareAheadOf(const Ahead& ahead, const Stats& stats) {
        ++m_log->levels;
        ++m_log->levelsAhead;
        const std::size_t gotStart =
            ahead.levelIndex < stats.levels.size() ? startOf(stats.levels[ahead.levelIndex], ahead.items) : ahead.items;
        compare(ahead.got, ahead.expected, {gotStart, ahead.expectedStart}, nullptr, {});
    }

    /// The items alive at a level's start (all, or those its start kept: a level described by its objects).
    static std::size_t startOf(const LevelStats& level, std::size_t items) {
        return level.itemsPerIteration.empty() ? items : level.itemsPerIteration.front();
    }

    /// The items alive at a level's start: GL's, the reference's.
    struct Starts {
        std::size_t got;
        std::size_t expected;
    };

    /// The items alive at the level's start; iteration by iteration, the view the tested backend used (fitted on the
    /// device after the first, and for the first too in a level described by its objects) and what it left, against
    /// the reference's; then the alive sets at the level's end, item by item (`gotAlive`, where the level was waited
    /// for).
    void compare(const std::vector<IterationTrace>& got, const std::vector<IterationTrace>& expected, Starts starts,
                 const std::vector<std::uint8_t>* gotAliveOrNull, const std::vector<std::uint8_t>& expectedAlive) {
        LockstepLog& log = *m_log;
        if (starts.got != starts.expected)
            note(0, "GL starts the level with " + std::to_string(starts.got) + " items alive, the reference with " +
                        std::to_string(starts.expected));
        std::size_t aliveBefore = starts.got;
        const std::size_t iterations = std::max(got.size(), expected.size());
        for (std::size_t i = 0; i < iterations; ++i) {
            ++log.iterations;
            if (i >= got.size() || i >= expected.size()) {
                note(i, "GL ran " + std::to_string(got.size()) + " iterations, the reference " +
                            std::to_string(expected.size()));
                break;
            }
            const IterationTrace& gotTrace = got[i];
            const IterationTrace& expectedTrace = expected[i];
            log.itemsIn += aliveBefore;
            log.itemsPruned += aliveBefore - std::min<std::size_t>(aliveBefore, gotTrace.result.alive);
            if (!sameView(gotTrace, expectedTrace))
                note(i, "the views differ" + viewDifference(gotTrace, expectedTrace));
            const IterationResult& g = gotTrace.result;
            const IterationResult& e = expectedTrace.result;
            const bool sameRange = g.ownerMin == e.ownerMin && g.ownerMax == e.ownerMax;
            const bool sameBounds = g.bounds.min == e.bounds.min && g.bounds.max == e.bounds.max;
            if (g.overflows != 0 || g.alive != e.alive || (e.alive != 0 && !(sameRange && sameBounds)))
                note(i, std::to_string(aliveBefore) + " items in, GL keeps " + std::to_string(g.alive) +
                            " (overflows " + std::to_string(g.overflows) + "), reference keeps " +
                            std::to_string(e.alive));
            aliveBefore = g.alive;
        }
        if (gotAliveOrNull == nullptr) return;
        const std::vector<std::uint8_t>& gotAlive = *gotAliveOrNull;
        std::size_t differing = 0;
        std::size_t firstDiffering = gotAlive.size();
        for (std::size_t i = 0; i < gotAlive.size() && i < expectedAlive.size(); ++i) {
            if (gotAlive[i] == expectedAlive[i]) continue;
            if (differing++ == 0) firstDiffering = i;
        }
        if (differing != 0 || gotAlive.size() != expectedAlive.size()) {
            log.itemsDiffering += differing;
            std::ostringstream s;
            s << "the survivors differ in " << differing << " items";
            if (differing != 0)
                s << " (first: item " << firstDiffering << ", GL " << int(gotAlive[firstDiffering]) << ", reference "
                  << int(expectedAlive[firstDiffering]) << ")";
            note(got.size(), s.str());
        }
    }

    static bool sameFloats(const float (&a)[3], const float (&b)[3]) {
        return std::memcmp(a, b, sizeof a) == 0;
    }

    static bool sameView(const IterationTrace& a, const IterationTrace& b) {
        const View& x = a.view;
        const View& y = b.view;
        return a.idBits == b.idBits && x.box.min == y.box.min && x.box.max == y.box.max && sameFloats(x.lo, y.lo) &&
               sameFloats(x.pixelScale, y.pixelScale) && sameFloats(x.depthScale, y.depthScale) &&
               sameFloats(x.halfSize, y.halfSize) && sameFloats(x.depthPad, y.depthPad);
    }

    static std::string viewDifference(const IterationTrace& a, const IterationTrace& b) {
        std::ostringstream s;
        s.precision(17);
        s << ": GL box min " << a.view.box.min.transpose() << " halfSize " << a.view.halfSize[0] << " idBits "
          << a.idBits << ", reference box min " << b.view.box.min.transpose() << " halfSize " << b.view.halfSize[0]
          << " idBits " << b.idBits;
        return s.str();
    }

    void note(std::size_t iteration, const std::string& what) {
        LockstepLog& log = *m_log;
        ++log.mismatches;
        if (log.details.size() < 8)
            log.details.push_back("level " + std::to_string(log.levels) + " iteration " + std::to_string(iteration) +
                                  ": " + what);
    }

    std::unique_ptr<PruningBackend> m_tested;
    std::unique_ptr<PruningBackend> m_reference;
    std::shared_ptr<LockstepLog> m_log;
    std::shared_ptr<std::vector<float>> m_devicePositions;  ///< GlBackendOptions::positionsAfterUpload
    std::shared_ptr<std::vector<float>> m_deviceBoxes;      ///< GlBackendOptions::boxesAfterUpload
    Stats m_scratch;  ///< what the checks cost is not the culler's
    LevelStats m_scratchLevel;
    std::vector<IterationTrace> m_got;
    std::vector<IterationTrace> m_expected;
    std::unique_ptr<Ahead> m_ahead;  ///< a level run ahead whose comparison waits for the next level
    std::vector<std::unique_ptr<Deferred>> m_deferred;  ///< since the last collect()
    std::vector<std::uint8_t> m_expectedAlive;
};

}  // namespace

std::string LockstepLog::summary() const {
    std::ostringstream s;
    s << levels << " levels, " << iterations << " iterations, " << itemsIn << " items in, " << itemsPruned
      << " pruned, " << uploads << " uploads (" << mappedVertices << " vertices mapped, " << builtBoxes
      << " boxes built on the device), "
      << mismatches << " differences (" << itemsDiffering << " items)";
    for (const std::string& d : details) s << "\n  " << d;
    return s.str();
}

PruningBackendFactory lockstepFactory(std::shared_ptr<LockstepLog> log, GlBackendOptions options) {
    return [log, options](const Settings& settings) -> std::unique_ptr<PruningBackend> {
        GlBackendOptions o = options;
        o.positionsAfterUpload = std::make_shared<std::vector<float>>();
        o.boxesAfterUpload = std::make_shared<std::vector<float>>();
        return std::make_unique<LockstepBackend>(createGlPruningBackend(settings, o),
                                                 createReferencePruningBackend(settings), log, o.positionsAfterUpload,
                                                 o.boxesAfterUpload);
    };
}

std::string lockstepName(const LockstepCase& c) {
    return std::string(c.pipeline == Pipeline::Paper ? "Paper" : "Auto") +
           (c.mode == Mode::Reliable ? "Reliable" : "Sampled") + (c.backend == Backend::Raster ? "Raster" : "Compute") +
           std::to_string(c.resolution) + (c.axes == 7 ? "" : "Axes" + std::to_string(c.axes)) +
           (c.margin == 0.0 ? "" : "Margin");
}

void PrintTo(const LockstepCase& c, std::ostream* os) { *os << lockstepName(c); }

Settings lockstepSettings(const LockstepCase& c) {
    Settings s;
    s.pipeline = c.pipeline;
    s.mode = c.mode;
    s.backend = c.backend;
    s.resolution = c.resolution;
    s.axes = c.axes;
    s.margin = c.margin;
    s.gpuLevels = GpuLevels::Always;
    s.exactThreshold = 0;  // every level runs
    // The paper's pipeline iterates until the set stops changing (both stop rules of the chain are held to the
    // reference: Auto's stop at the default minPruneFraction).
    if (c.pipeline == Pipeline::Paper) s.minPruneFraction = 0.0;
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
