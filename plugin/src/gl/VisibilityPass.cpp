#include "gl/VisibilityPass.h"

#include "bindings.h"
#include "gl/GlBuffers.h"
#include "gl/LevelDevice.h"
#include "gl/ViewRecords.h"
#include "CullerBackends.h"
#include "VisibilityLevel.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cullide::gl {
namespace {

/// A level run ahead (pruneLevelAhead) whose chain has not been read back yet.
struct AheadLevel {
    std::size_t levelIndex = 0;  ///< into Stats::levels
    std::size_t place = 0;
    int issued = 0;
    std::vector<IterationTrace>* trace = nullptr;
};

}  // namespace

/// The policy over the device's steps (LevelDevice): how many iterations a level issues, when it waits, which level
/// runs ahead and what happens when one stopped early.
struct VisibilityPass::Impl : LevelDevice {
    using LevelDevice::LevelDevice;

    /// Per place of a frame (LevelStart::place): how many iterations a level there issues before its read-back, the
    /// most the levels there ran over the last frames (a level whose count goes up and down then never waits twice:
    /// the iterations issued past the end of its chain cost empty dispatches, a second read-back a round trip).
    struct PlaceHistory {
        int guess = 0;       ///< 0: nothing ran there yet (all that are allowed)
        int sinceGuess = 0;  ///< levels there since one ran `guess` iterations
        bool wait = false;   ///< the level run ahead there stopped early: waited for until it runs as one chain
    };
    std::vector<PlaceHistory> places;
    std::optional<AheadLevel> ahead;  ///< a level run ahead, not read back yet

    int guessFor(std::size_t place) const {
        const int guess = place < places.size() ? places[place].guess : 0;
        return guess > 0 ? guess : settings.maxIterations;
    }

    /// A level in `place` ran `ran` iterations (`oneChain`: in one chain, read back once).
    void remember(std::size_t place, int ran, bool oneChain) {
        constexpr int kWindow = 16;  // levels over which the most iterations run is kept
        if (place >= places.size()) places.resize(place + 1);
        PlaceHistory& h = places[place];
        if (ran >= h.guess || ++h.sinceGuess > kWindow) {
            h.guess = ran;
            h.sinceGuess = 0;
        }
        h.wait = !oneChain;
    }

    /// The level on the device, waited for: issued (issueLevel), then each chain of its iterations read back once.
    /// The device stops the chain itself, so iterations issued past its end cost only empty dispatches, too few a
    /// second read-back. The chain also stops where the records need building again: for a view that shrank to a
    /// quarter (built for it, and the chain goes on) or where they did not fit (the buffers grow, and the iteration
    /// runs again). Throws LevelsRerun where the level run ahead before it (its parents) stopped early.
    void runLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                  LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) {
        const int maxIterations = settings.maxIterations;
        int issued = issueLevel(items, start, guessFor(start.place), level, stats);
        int next = 0;  // the first iteration of the chain being waited for
        bool built = true;
        bool oneChain = true;
        int shortBuilds = 0;
        for (;;) {
            waitForChain(ahead.has_value(), level, stats);
            if (ahead) finishAhead(stats, true);
            const Chain chain{readScratch.data() + CULLIDE_DISPATCH_RECORDS};
            const int ran = chain.ran();
            if (ran <= next || ran > issued) throw BackendError("the device's chain of iterations did not run");
            level.idleIterations += static_cast<std::size_t>(issued - ran);
            next = ran;
            if (chain.shortBuild()) {  // iteration ran - 1 pruned nothing: build again, rerun it
                if (++shortBuilds > 2) throw BackendError("the record buffers were short after growing twice");
                level.shortBuilds += 1;
                float approx = 0.0f;
                const std::uint32_t approxBits = chain[CULLIDE_DISPATCH_NEEDED_APPROX];
                std::memcpy(&approx, &approxBits, sizeof approx);
                growRecords(chain[CULLIDE_DISPATCH_NEEDED], approx);
                next = ran - 1;
            } else {
                if (built) level.records += chain[CULLIDE_DISPATCH_NEEDED];
                built = false;
                if (chain.levelEnded()) break;
            }
            oneChain = false;
            // Records for the next view (a refit) or again (short); the chain goes on from `next`: to the end where
            // the batch was too short.
            if (chain.shortBuild() || chain.stop() == CULLIDE_STOP_REFIT) {
                buildRecords(next, false, level, stats);  // the items' boxes are built already
                built = true;
            }
            const int guess = std::max(guessFor(start.place), next + 1);
            issued = chain.stop() == CULLIDE_STOP_NONE ? maxIterations : std::min(maxIterations, guess);
            for (int i = next; i < issued; ++i) issueIteration(i, level, stats);
        }
        const Chain chain{readScratch.data() + CULLIDE_DISPATCH_RECORDS};
        remember(start.place, chain.ran(), oneChain);
        noteIterations(chain, level);
        readSurvivors(chain.stop(), survivors);
        if (trace) readTrace(buffers[kViews], chain.ran(), *trace);
    }

    /// A level run ahead: issued, its chain and views kept for the next level's read-back (nothing waits). Where the
    /// level in its place stopped early last time, it is waited for instead.
    void runAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                  std::vector<IterationTrace>* trace) {
        LevelStats& level = stats.levels[levelIndex];
        if (start.place < places.size() && places[start.place].wait) {
            std::vector<std::uint8_t> survivors;
            runLevel(items, start, survivors, level, stats, trace);
            return;
        }
        const int issued = issueLevel(items, start, guessFor(start.place), level, stats);
        reserveBuffer(buffers[kStash], capacity[kStash], 4 * kChainWords);
        glCopyNamedBufferSubData(buffers[kCounters], buffers[kStash], 4 * CULLIDE_DISPATCH_RECORDS, 0,
                                 4 * kChainWords);
        if (trace) {
            const std::size_t bytes = sizeof(ViewRecord) * static_cast<std::size_t>(issued);
            reserveBuffer(buffers[kStashViews], capacity[kStashViews], bytes);
            glCopyNamedBufferSubData(buffers[kViews], buffers[kStashViews], 0, 0, static_cast<GLsizeiptr>(bytes));
        }
        endTiming();  // its device time is in the next level's span
        ahead = AheadLevel{levelIndex, start.place, issued, trace};
        checkGlError("a level run ahead");
    }

    /// The level run ahead, from the chain read back with the next level's (`inReadBack`) or on its own: its stats
    /// and trace. Where it stopped early (records to build again, more iterations needed) it is waited for next time
    /// and, when a level inherited its survivors, both run again (LevelsRerun).
    void finishAhead(Stats& stats, bool inReadBack) {
        const AheadLevel a = *ahead;
        ahead.reset();
        std::vector<std::uint32_t> own;
        const std::uint32_t* words = nullptr;
        if (inReadBack) {
            words = readScratch.data() + CULLIDE_AHEAD;
        } else {
            own.resize(kChainWords);
            readBack(buffers[kStash], 0, 4 * kChainWords, own.data(), stats.levels[a.levelIndex], stats);
            words = own.data();
        }
        const Chain chain{words};
        LevelStats& level = stats.levels[a.levelIndex];
        const int ran = chain.ran();
        if (ran < 1 || ran > a.issued) throw BackendError("the device's chain of iterations did not run");
        const bool early = !chain.levelEnded();
        level.idleIterations += static_cast<std::size_t>(a.issued - ran);
        if (chain.shortBuild()) level.shortBuilds += 1;
        else level.records += chain[CULLIDE_DISPATCH_NEEDED];
        if (early) {  // how many it needs is not known: waited for next time, which finds out
            if (a.place >= places.size()) places.resize(a.place + 1);
            places[a.place].wait = true;
        } else {
            remember(a.place, ran, true);
        }
        noteIterations(chain, level);
        if (a.trace) readTrace(buffers[kStashViews], ran, *a.trace);
        if (early && inReadBack) throw LevelsRerun{};
    }

    /// The level's iterations into its stats, from the chain's items alive at its start (all, or those whose parent
    /// survived) and after each iteration.
    static void noteIterations(const Chain& chain, LevelStats& level) {
        std::size_t before = chain[CULLIDE_CHAIN_ALIVE_START];
        if (!level.itemsPerIteration.empty()) level.itemsPerIteration.front() = before;
        const int ran = chain.ran();
        for (int i = 0; i < ran; ++i) {
            const bool last = i + 1 == ran;
            const std::size_t after = chain[CULLIDE_CHAIN_ALIVE + i];
            const Step step = !last ? Step::Next
                                    : (chain.stop() == CULLIDE_STOP_ONE_OWNER ? Step::AllPruned : Step::Stop);
            noteIteration(level, before, after, step);
            before = after;
        }
        level.primitivesDrawn += 3 * 3 * std::size_t{chain[CULLIDE_CHAIN_RECORDS_RUN]};  // 3 passes, 3 views
    }
};


VisibilityPass::VisibilityPass(const Settings& settings, const GlBackendOptions& options)
    : m_impl(std::make_unique<Impl>(std::make_unique<EglContext>(settings.device), settings, options)) {}

VisibilityPass::~VisibilityPass() = default;

std::string VisibilityPass::renderer() const { return m_impl->context.renderer(); }
std::string VisibilityPass::device() const { return m_impl->context.device(); }

void VisibilityPass::upload(const GpuGeometry& geometry, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    s.uploadPositions(geometry, stats);
    stats.bytesUploaded += uploadAfterPrefix(s.buffers[kIndices], s.capacity[kIndices], s.valid[kIndices],
                                             geometry.indices.data(), geometry.indices.size() * 4,
                                             geometry.keptIndices * 4);
    stats.bytesUploaded += uploadAfterPrefix(s.buffers[kOrdered], s.capacity[kOrdered], s.valid[kOrdered],
                                             geometry.ordered.data(), geometry.ordered.size() * 4,
                                             geometry.keptOrdered * 4);
    uploadBuffer(s.buffers[kBoxes], s.capacity[kBoxes], geometry.boxes.data(), geometry.boxes.size() * 4);
    stats.bytesUploaded += geometry.boxes.size() * 4;
    s.geometry = &geometry;
    s.ahead.reset();  // a cluster starts: a level run ahead before belongs to an abandoned frame
}

std::size_t VisibilityPass::deviceBytes() const {
    const Impl& s = *m_impl;
    std::size_t bytes = 4 * std::size_t{4} * 3 * static_cast<std::size_t>(s.settings.resolution) *
                        static_cast<std::size_t>(s.settings.resolution);  // four r32ui images, three views wide
    for (const std::size_t c : s.capacity) bytes += c;
    return bytes;
}

void VisibilityPass::forgetUploads() {
    // After a GL error (out of memory among them) no buffer is trusted to hold what was sent or the size it was
    // asked for: the next frame allocates and sends everything again.
    Impl& s = *m_impl;
    for (std::size_t& v : s.valid) v = 0;
    for (std::size_t& c : s.capacity) c = 0;
    s.recordCapacity = 0;
    s.places.clear();
    s.ahead.reset();
    s.lastItemCount = 0;
}

void VisibilityPass::pruneLevel(const LevelItems& items, const LevelStart& start, std::vector<std::uint8_t>& survivors,
                                LevelStats& level, Stats& stats, std::vector<IterationTrace>* trace) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    s.runLevel(items, start, survivors, level, stats, trace);
}

void VisibilityPass::pruneLevelAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex,
                                     Stats& stats, std::vector<IterationTrace>* trace) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    s.ahead.reset();  // one never waited for belongs to an abandoned frame
    s.runAhead(items, start, levelIndex, stats, trace);
}

void VisibilityPass::settle(Stats& stats) {
    Impl& s = *m_impl;
    if (!s.ahead) return;
    s.context.makeCurrent();
    s.finishAhead(stats, false);
}

}  // namespace cullide::gl

namespace cullide {

std::unique_ptr<PruningBackend> createGlPruningBackend(const Settings& settings, const GlBackendOptions& options) {
    return std::make_unique<gl::VisibilityPass>(settings, options);
}

}  // namespace cullide
