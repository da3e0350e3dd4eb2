#include "gl/VisibilityPass.h"

#include "bindings.h"
#include "gl/GlBuffers.h"
#include "gl/GpuTimes.h"
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

/// A level issued without waiting (run ahead, or deferred) whose chain has not been read back yet.
struct IssuedLevel {
    std::size_t levelIndex = 0;  ///< into Stats::levels
    std::size_t place = 0;
    int issued = 0;
    std::vector<IterationTrace>* trace = nullptr;
    std::size_t span = kNoSpan;  ///< its timer query span (LevelDevice::spans), opened at `spanOpened`
    Clock::time_point spanOpened;
};

/// The ViewRecords of a level's views (as kViews holds them).
constexpr std::size_t kViewsEach = CULLIDE_MAX_ITERATIONS + 1;

/// A level whose read-back is deferred to the frame's collect (pruneLevelDeferred): where its words are.
struct DeferredEntry {
    IssuedLevel level;
    std::size_t items = 0;
    std::size_t firstWord = 0;  ///< its counter words (counterWords(items)) in kFrameResults
    std::size_t firstView = 0;  ///< its views, then those of the level run ahead, in kFrameViews (with a trace)
    std::optional<IssuedLevel> ahead;  ///< the level run ahead before it: its chain in words CULLIDE_AHEAD ..
    bool waited = false;  ///< it ran waited for (its place stopped early last time): `survivors` holds its result
    std::vector<std::uint8_t> survivors;
    bool exact = false;         ///< the device exact stage ran after it
    std::size_t exactWord = 0;  ///< where kFrameResults holds the frame's exact pairs counted after it
    std::size_t exactSpan = kNoSpan;  ///< the exact stage's timer query span, opened at `exactSpanOpened`
    Clock::time_point exactSpanOpened;
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
        bool wait = false;   ///< the level run ahead or deferred there stopped early: waited for until it runs as one
                             ///< chain
        float perBand = 0.0f;  ///< short bands: the pixels per band the last build there found (0: none yet)
    };
    std::vector<PlaceHistory> places;
    std::optional<IssuedLevel> ahead;  ///< a level run ahead, not read back yet
    std::vector<DeferredEntry> deferred;  ///< levels whose read-back waits for collect(), in order
    std::size_t frameWords = 0;           ///< words of kFrameResults they fill
    std::size_t frameViews = 0;           ///< ViewRecords of kFrameViews they fill
    std::vector<std::uint32_t> frameScratch;  ///< collect()'s read-back
    bool exactIssued = false;                 ///< an exact stage ran since the last collect(): kExact is counting
    std::vector<std::uint32_t> exactScratch;  ///< collect()'s exact pairs

    bool waitsAt(std::size_t place) const { return place < places.size() && places[place].wait; }

    float perBandFor(std::size_t place) const { return place < places.size() ? places[place].perBand : 0.0f; }

    /// The pixels per band of short bands the level's last build found, for the next build in its place.
    void learnPerBand(std::size_t place, const Chain& chain) {
        float perBand = 0.0f;
        const std::uint32_t bits = chain[CULLIDE_CHAIN_PER_BAND];
        std::memcpy(&perBand, &bits, sizeof perBand);
        if (!(perBand > 0.0f)) return;  // no short-band build (also NaN)
        if (place >= places.size()) places.resize(place + 1);
        places[place].perBand = perBand;
    }

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
        int issued = issueLevel(items, start, guessFor(start.place), perBandFor(start.place), level, stats);
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
                growRecordsFor(chain);
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
        learnPerBand(start.place, chain);
        noteIterations(chain, level);
        readSurvivors(chain.stop(), survivors);
        if (trace) readTrace(buffers[kViews], 0, chain.ran(), *trace);
    }

    /// A level run ahead: issued, its chain and views kept for the next level's read-back (nothing waits). Where the
    /// level in its place stopped early last time, it is waited for instead.
    void runAhead(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                  std::vector<IterationTrace>* trace) {
        LevelStats& level = stats.levels[levelIndex];
        if (waitsAt(start.place)) {
            std::vector<std::uint8_t> survivors;
            runLevel(items, start, survivors, level, stats, trace);
            return;
        }
        const int issued = issueLevel(items, start, guessFor(start.place), perBandFor(start.place), level, stats);
        reserveBuffer(buffers[kStash], capacity[kStash], 4 * kChainWords);
        glCopyNamedBufferSubData(buffers[kCounters], buffers[kStash], 4 * CULLIDE_DISPATCH_RECORDS, 0,
                                 4 * kChainWords);
        if (trace) {
            const std::size_t bytes = sizeof(ViewRecord) * static_cast<std::size_t>(issued);
            reserveBuffer(buffers[kStashViews], capacity[kStashViews], bytes);
            glCopyNamedBufferSubData(buffers[kViews], buffers[kStashViews], 0, 0, static_cast<GLsizeiptr>(bytes));
        }
        endTiming();  // its span ends here: read after the read-back that brings its chain
        ahead = IssuedLevel{levelIndex, start.place, issued, trace, lastSpan(), timedSpan};
        checkGlError("a level run ahead");
    }

    /// The level run ahead, from the chain read back with the next level's (`inReadBack`) or on its own: its stats
    /// and trace. Where it stopped early (records to build again, more iterations needed) it is waited for next time
    /// and, when a level inherited its survivors, both run again (LevelsRerun).
    void finishAhead(Stats& stats, bool inReadBack) {
        const IssuedLevel a = *ahead;
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
        const bool ended = noteIssued(a, Chain{words}, buffers[kStashViews], 0, stats);
        if (!ended && inReadBack) throw LevelsRerun{};
    }

    /// A level issued without waiting, from its chain as read back: its stats, its device time and (from ViewRecord
    /// `firstView` of `views` on) its trace. Returns whether it ended as one chain; otherwise its place waits for it
    /// next time.
    bool noteIssued(const IssuedLevel& a, const Chain& chain, GLuint views, std::size_t firstView, Stats& stats) {
        LevelStats& level = stats.levels[a.levelIndex];
        const int ran = chain.ran();
        if (ran < 1 || ran > a.issued) throw BackendError("the device's chain of iterations did not run");
        level.idleIterations += static_cast<std::size_t>(a.issued - ran);
        if (chain.shortBuild()) {  // the record buffers grow for the level that runs again
            level.shortBuilds += 1;
            growRecordsFor(chain);
        } else {
            level.records += chain[CULLIDE_DISPATCH_NEEDED];
        }
        learnPerBand(a.place, chain);
        const bool ended = chain.levelEnded();
        if (ended) {
            remember(a.place, ran, true);
        } else {
            if (a.place >= places.size()) places.resize(a.place + 1);
            places[a.place].wait = true;
        }
        noteIterations(chain, level);
        recordGpuTime(spanMs(a.span, a.spanOpened), level, stats);
        if (a.trace) readTrace(views, firstView, ran, *a.trace);
        return ended;
    }

    /// A level whose read-back is deferred: issued, and its counter words (with the chain of the level run ahead
    /// before it) and, for a trace, its views copied aside on the device for collect(). Where the level in its place
    /// stopped early last time it is waited for at once instead.
    void runDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex, Stats& stats,
                     std::vector<IterationTrace>* trace) {
        LevelStats& level = stats.levels[levelIndex];
        DeferredEntry entry;
        entry.level.levelIndex = levelIndex;
        entry.level.place = start.place;
        entry.level.trace = trace;
        entry.items = items.size();
        if (waitsAt(start.place)) {
            runLevel(items, start, entry.survivors, level, stats, trace);
            entry.waited = true;
            deferred.push_back(std::move(entry));
            return;
        }
        entry.level.issued = issueLevel(items, start, guessFor(start.place), perBandFor(start.place), level, stats);
        level.deferred = true;
        endTiming();  // the level's span: its device time is read after collect()'s read-back
        entry.level.span = lastSpan();
        entry.level.spanOpened = timedSpan;
        if (items.exact.run) {
            startTiming();  // a span of its own (LevelStats::exactGpuMs)
            findExactPairs(items, !exactIssued, level, stats);
            endTiming();
            entry.exactSpan = lastSpan();
            entry.exactSpanOpened = timedSpan;
            exactIssued = true;
            entry.exact = true;
        }
        const std::size_t words = counterWords(items.size());
        if (ahead) {
            glCopyNamedBufferSubData(buffers[kStash], buffers[kCounters], 0, 4 * CULLIDE_AHEAD, 4 * kChainWords);
            entry.ahead = ahead;
            ahead.reset();
        }
        entry.firstWord = frameWords;
        const std::size_t exactWords = entry.exact ? 1 : 0;  // the frame's exact pairs so far
        growKeeping(buffers[kFrameResults], capacity[kFrameResults], 4 * frameWords,
                    4 * (frameWords + words + exactWords));
        glCopyNamedBufferSubData(buffers[kCounters], buffers[kFrameResults], 0,
                                 static_cast<GLintptr>(4 * frameWords), static_cast<GLsizeiptr>(4 * words));
        if (entry.exact) {
            entry.exactWord = frameWords + words;
            glCopyNamedBufferSubData(buffers[kExact], buffers[kFrameResults], 0,
                                     static_cast<GLintptr>(4 * entry.exactWord), 4);
        }
        frameWords += words + exactWords;
        if (trace || (entry.ahead && entry.ahead->trace)) {
            const std::size_t firstView = frameViews;
            entry.firstView = firstView;
            frameViews += 2 * kViewsEach;
            growKeeping(buffers[kFrameViews], capacity[kFrameViews], sizeof(ViewRecord) * firstView,
                        sizeof(ViewRecord) * (firstView + 2 * kViewsEach));
            glCopyNamedBufferSubData(buffers[kViews], buffers[kFrameViews], 0,
                                     static_cast<GLintptr>(sizeof(ViewRecord) * firstView),
                                     sizeof(ViewRecord) * kViewsEach);
            if (entry.ahead && entry.ahead->trace)
                glCopyNamedBufferSubData(buffers[kStashViews], buffers[kFrameViews], 0,
                                         static_cast<GLintptr>(sizeof(ViewRecord) * (firstView + kViewsEach)),
                                         static_cast<GLsizeiptr>(sizeof(ViewRecord) *
                                                                 static_cast<std::size_t>(entry.ahead->issued)));
        }
        deferred.push_back(std::move(entry));
        checkGlError("a deferred level");
    }

    /// One read-back for every deferred level (at most until `until`), then each one's stats, trace and result.
    bool collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) {
        const DeferredEntry* lastIssued = nullptr;
        for (const DeferredEntry& e : deferred)
            if (!e.waited) lastIssued = &e;
        if (lastIssued) {
            // The read-back (its wait in its CPU time too) is the last issued level's: it is the one waited for.
            const auto waitStart = Clock::now();
            LevelStats& last = stats.levels[lastIssued->level.levelIndex];
            frameScratch.resize(frameWords);
            const bool done =
                readBack(buffers[kFrameResults], 0, 4 * frameWords, frameScratch.data(), last, stats, until);
            last.cpuMs += msSince(waitStart);
            if (!done) {
                dropDeferred();
                forgetSpans();
                return false;
            }
            checkGlError("the deferred levels");
            readExactPairs(stats);
        }
        results.resize(deferred.size());
        std::size_t exactFrom = 0;  // the frame's exact pairs before the level's
        for (std::size_t k = 0; k < deferred.size(); ++k) {
            results[k] = noteDeferred(deferred[k], stats);
            if (deferred[k].exact) takeExactPairs(deferred[k], exactFrom, results[k], stats);
        }
        dropDeferred();
        forgetSpans();
        return true;
    }

    /// A deferred level from collect()'s read-back: its stats and trace, and its survivors where it (and the level
    /// run ahead before it) ended as one chain; otherwise its place waits for it next time.
    DeferredLevel noteDeferred(DeferredEntry& e, Stats& stats) {
        DeferredLevel result;
        if (e.waited) {
            result.complete = true;
            result.survivors = std::move(e.survivors);
            return result;
        }
        const std::uint32_t* words = frameScratch.data() + e.firstWord;
        const bool aheadEnded = !e.ahead || noteIssued(*e.ahead, Chain{words + CULLIDE_AHEAD}, buffers[kFrameViews],
                                                       e.firstView + kViewsEach, stats);
        const Chain chain{words + CULLIDE_DISPATCH_RECORDS};
        const bool ended = noteIssued(e.level, chain, buffers[kFrameViews], e.firstView, stats);
        if (e.exact)
            recordExactGpuTime(spanMs(e.exactSpan, e.exactSpanOpened), stats.levels[e.level.levelIndex], stats);
        // It needed more iterations than were issued: the rerun issues all that are allowed.
        if (!ended && !chain.shortBuild() && chain.stop() == CULLIDE_STOP_NONE)
            remember(e.level.place, settings.maxIterations, false);
        result.complete = ended && aheadEnded;
        if (result.complete) survivorsFrom(words + CULLIDE_ALIVE_BITS, e.items, chain.stop(), result.survivors);
        return result;
    }

    /// The frame's exact pairs, after collect()'s read-back: the device has finished writing them, so this read
    /// waits for nothing. Where they did not all fit, the buffer grows for the next frame.
    void readExactPairs(Stats& stats) {
        std::size_t total = 0;
        for (const DeferredEntry& e : deferred)
            if (e.exact && !e.waited) total = frameScratch[e.exactWord];
        const std::size_t held = std::min(total, exactCapacity);
        exactScratch.resize(2 * held);
        if (held > 0) {
            glGetNamedBufferSubData(buffers[kExact], 4, static_cast<GLsizeiptr>(8 * held), exactScratch.data());
            stats.bytesReadBack += 8 * held;
            checkGlError("the exact pairs");
        }
        constexpr std::size_t kMostPairs = std::size_t{1} << 25;  // 256 MiB of pairs
        if (total > exactCapacity) exactCapacity = std::min(kMostPairs, std::max(exactCapacity, total + total / 4));
    }

    /// A deferred level's exact pairs (those counted after the level before's, from `from`), where they all fit.
    void takeExactPairs(const DeferredEntry& e, std::size_t& from, DeferredLevel& result, Stats& stats) const {
        const std::size_t to = frameScratch[e.exactWord];
        if (2 * to > exactScratch.size()) {  // some of its pairs were not written: its exact stage runs on the CPU
            ++stats.deviceExactOverflows;
        } else if (result.complete) {
            result.exactRan = true;
            result.exactPairs.assign(exactScratch.begin() + static_cast<std::ptrdiff_t>(2 * from),
                                     exactScratch.begin() + static_cast<std::ptrdiff_t>(2 * to));
        }
        from = to;
    }

    /// Grows the record buffers for the count a short build needed (as the chain says).
    void growRecordsFor(const Chain& chain) {
        float approx = 0.0f;
        const std::uint32_t approxBits = chain[CULLIDE_DISPATCH_NEEDED_APPROX];
        std::memcpy(&approx, &approxBits, sizeof approx);
        growRecords(chain[CULLIDE_DISPATCH_NEEDED], approx);
    }

    /// Forgets the deferred levels (no GL call).
    void dropDeferred() {
        exactIssued = false;
        deferred.clear();
        frameWords = 0;
        frameViews = 0;
    }

    /// The level's iterations into its stats, from the chain's items alive at its start (all, or those whose parent
    /// survived) and after each iteration. Throws BackendError where an iteration miscounted its items.
    static void noteIterations(const Chain& chain, LevelStats& level) {
        if (chain.miscounted()) throw BackendError("an iteration on the device did not decide every alive item once");
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

void VisibilityPass::beginFrame() {
    Impl& s = *m_impl;
    s.ahead.reset();
    s.context.makeCurrent();
    s.dropDeferred();
    s.forgetSpans();  // a span that a frame abandoned half way left open is closed
}

void VisibilityPass::upload(const GpuGeometry& geometry, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    const bool timed = !s.timing;  // a span of its own (Stats::uploadGpuMs), where none is open
    if (timed) s.startTiming();
    s.uploadPositions(geometry, stats);
    stats.bytesUploaded += uploadAfterPrefix(s.buffers[kIndices], s.capacity[kIndices], s.valid[kIndices],
                                             geometry.indices.data(), geometry.indices.size() * 4,
                                             geometry.keptIndices * 4);
    stats.bytesUploaded += uploadAfterPrefix(s.buffers[kOrdered], s.capacity[kOrdered], s.valid[kOrdered],
                                             geometry.ordered.data(), geometry.ordered.size() * 4,
                                             geometry.keptOrdered * 4);
    s.uploadBoxes(geometry, stats);
    if (timed) {
        s.endTiming();
        if (s.lastSpan() != kNoSpan) s.uploadSpans.emplace_back(s.lastSpan(), s.timedSpan);
    }
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

bool VisibilityPass::hardwareDevice() const { return !m_impl->context.isSoftware(); }

void VisibilityPass::forgetUploads() {
    // After a GL error (out of memory among them) no buffer is trusted to hold what was sent or the size it was
    // asked for: the next frame allocates and sends everything again.
    Impl& s = *m_impl;
    for (std::size_t& v : s.valid) v = 0;
    s.heldBoxes.clear();
    s.heldRanges.clear();
    for (std::size_t& c : s.capacity) c = 0;
    s.recordCapacity = 0;
    s.places.clear();
    s.ahead.reset();
    s.dropDeferred();
    s.capacity[kFrameResults] = 0;
    s.capacity[kFrameViews] = 0;
    s.capacity[kExact] = 0;
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

void VisibilityPass::pruneLevelDeferred(const LevelItems& items, const LevelStart& start, std::size_t levelIndex,
                                        Stats& stats, std::vector<IterationTrace>* trace) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    s.runDeferred(items, start, levelIndex, stats, trace);
}

bool VisibilityPass::collect(const Deadline& until, std::vector<DeferredLevel>& results, Stats& stats) {
    Impl& s = *m_impl;
    results.clear();
    if (s.deferred.empty()) return true;
    s.context.makeCurrent();
    return s.collect(until, results, stats);
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
