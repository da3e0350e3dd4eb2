// The device side of CULLIDE's visibility levels (OpenGL 4.5 through headless EGL): the programs, buffers and images,
// and the steps a level is made of — its items and first view sent (or its ranges, and start.comp), its records built
// (build.comp), an iteration
// issued (three passes, and on the raster back-end a set-up and a survivor pass, dispatched indirectly: nothing
// waits), the chain read back. gl::VisibilityPass
// decides which steps run and when it waits. GL code: only under plugin/src/gl.
#pragma once

#include "CullerBackends.h"
#include "Deadline.h"
#include "PruningBackend.h"
#include "bindings.h"
#include "cullide/Settings.h"
#include "gl/EglContext.h"
#include "gl/GlApi.h"

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace cullide::gl {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0);

enum Buffer {
    kPositions,
    kIndices,
    kBoxes,
    kPrims,
    kPrimsNext,  ///< the records of the items alive, packed (the compute back-end's nearest pass, survive.comp);
                 ///< swapped with kPrims
    kOwners,
    kFlags,
    kRecords,
    kCounters,
    kAlive,
    kItemBounds,
    kPrimBegin,
    kItemPrims,
    kBands,
    kBuild,
    kViews,
    kRanges,       ///< a level described by its objects: its ranges, then their partners' boxes
    kParentAlive,  ///< the last level's alive set (copied on the device), where a level inherits it
    kStash,       ///< a level run ahead: words CULLIDE_DISPATCH_RECORDS .. CULLIDE_AHEAD of its counters
    kStashViews,  ///< ... and its views (where a trace is asked for)
    kLocal,       ///< the mapped meshes' own vertices (double)
    kMapped,      ///< their MappedRecords
    kOrdered,     ///< GpuGeometry::ordered
    kBoxRanges,   ///< GpuGeometry::builtRanges
    kFrameResults,  ///< the deferred levels' counter words (chain, the level run ahead's chain, alive bits), in turn
    kFrameViews,    ///< ... and their views and those of the levels run ahead (where a trace is asked for)
    kExact,         ///< the frame's exact pairs (exact.comp, CULLIDE_SSBO_EXACT)
    kExactItems,    ///< the items of a level that start alive, where the exact stage follows it
    kBufferCount
};

/// Words of the counter buffer for a level of `items` items: counters, dispatch block, chain, the chain of a level
/// run ahead and a bit per item.
std::size_t counterWords(std::size_t items);

/// The words of a level's chain that a level run ahead keeps (kStash) until the next level's read-back.
constexpr std::size_t kChainWords = CULLIDE_AHEAD - CULLIDE_DISPATCH_RECORDS;

/// A level's chain as read back: word w of its counter buffer (CULLIDE_DISPATCH_RECORDS <= w < CULLIDE_AHEAD).
struct Chain {
    const std::uint32_t* words;  ///< word CULLIDE_DISPATCH_RECORDS
    std::uint32_t operator[](int w) const { return words[w - CULLIDE_DISPATCH_RECORDS]; }
    int ran() const { return static_cast<int>((*this)[CULLIDE_CHAIN_RAN]); }
    std::uint32_t stop() const { return (*this)[CULLIDE_CHAIN_STOP]; }
    bool shortBuild() const { return (*this)[CULLIDE_DISPATCH_SHORT] != 0; }
    /// An iteration decided fewer or more items than were alive at its start (a device fault).
    bool miscounted() const { return (*this)[CULLIDE_CHAIN_MISCOUNTED] != 0; }
    /// The level ended (its set stopped changing, one owner is left, or it ran every iteration allowed: the device
    /// stops with CULLIDE_STOP_DONE there) rather than stopping for records to build again or running past the
    /// iterations issued.
    bool levelEnded() const {
        return !shortBuild() && (stop() == CULLIDE_STOP_DONE || stop() == CULLIDE_STOP_ONE_OWNER);
    }
};

/// A level's alive set as 0/1 per item from its alive bits as read back (CULLIDE_ALIVE_BITS on; every item pruned
/// where the chain stopped with one owner left).
void survivorsFrom(const std::uint32_t* bits, std::size_t items, std::uint32_t stop,
                   std::vector<std::uint8_t>& survivors);

/// No timer query span (LevelDevice::spans).
constexpr std::size_t kNoSpan = static_cast<std::size_t>(-1);

/// One GL context's programs and resources for the visibility levels, and the steps a level is made of. Every public
/// step expects the context current on the calling thread.
struct LevelDevice {
    std::unique_ptr<EglContext> ownContext;
    EglContext& context;
    Settings settings;
    GLuint program = 0;
    GLuint setupProgram = 0;  // raster back-end only
    GLuint surviveProgram = 0;
    GLuint secondProgram = 0;  ///< compute back-end: the second pass (second.comp)
    GLuint flagProgram = 0;    ///< compute back-end: the flag pass, which ends the iteration (flag.comp)
    GLuint buildProgram = 0;
    GLuint mapProgram = 0;
    GLuint boxesProgram = 0;  ///< group_boxes.comp
    GLuint startProgram = 0;  ///< start.comp: the start of a level described by its objects
    GLuint exactProgram = 0;  ///< exact.comp: the device exact stage
    int bands = CULLIDE_BANDS_NONE;  ///< build.comp's CULLIDE_BANDS_* for this back-end and device
    GLuint vao = 0;
    GLuint framebuffer = 0;
    GLuint images[4] = {};
    GLuint buffers[kBufferCount] = {};
    std::size_t capacity[kBufferCount] = {};
    std::vector<unsigned char> heldBoxes;   ///< the boxes the device holds, as last sent (uploadChanged)
    std::vector<unsigned char> heldRanges;  ///< GpuGeometry::builtRanges as last sent
    std::size_t valid[kBufferCount] = {};  ///< bytes of the buffer that hold the last upload (positions, indices)
    bool hasTimers = false;      ///< timer queries (GL_TIME_ELAPSED) are there
    std::vector<GLuint> timers;  ///< one per span of the frame, made as needed
    std::size_t maxGroups = 65535;  ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    std::vector<std::uint32_t> readScratch;  ///< a level's read-back: counters, dispatch block, chain, alive bits
    const GpuGeometry* geometry = nullptr;
    const LevelItems* levelItems = nullptr;  ///< the level being pruned
    std::size_t lastItemCount = 0;  ///< of the last level (what the next level's items may inherit)
    bool onePrimEach = false;       ///< the level's item i is primitive i: its primBegin is not sent
    std::vector<std::uint32_t> rangeWords;  ///< kRanges' words, gathered before they are sent
    std::size_t exactPartnersWord = 0;  ///< where the level's exact partners begin in kRanges
    /// The pairs kExact holds: kept between frames, grown after a frame whose pairs did not fit.
    std::size_t exactCapacity = 65536;
    /// Short bands: the pixels per band the level's builds take, from the last build in its place (0: none).
    float perBandEstimate = 0.0f;
    /// Records the record buffers (kPrims, kPrimsNext; kRecords on the raster back-end) hold: kept between levels and
    /// frames, grown when a build needs more (the iteration then runs again).
    std::size_t recordCapacity = 0;
    /// The timer query spans of the frame so far (timers[0 .. spans)); the last one is open while `timing`. A
    /// span runs from a level's first pass to its read-back, or to the end of its issue where it is read back later
    /// (a deferred level), or where nothing reads it (a level run ahead: its device time is not measured). The device
    /// exact stage after a deferred level has a span of its own.
    std::size_t spans = 0;
    bool timing = false;
    Clock::time_point timedSpan;  ///< when the last span opened
    /// The uploads' spans not read yet (span, when it opened): read after the next blocking read-back
    /// (Stats::uploadGpuMs), forgotten with the frame's spans.
    std::vector<std::pair<std::size_t, Clock::time_point>> uploadSpans;
    double readBackDelayMs = 0.0;  ///< GlBackendOptions::readBackDelayMs (tests: a slow device's round trip)
    std::shared_ptr<std::vector<float>> positionsAfterUpload;  ///< GlBackendOptions::positionsAfterUpload (tests)
    std::shared_ptr<std::vector<float>> boxesAfterUpload;      ///< GlBackendOptions::boxesAfterUpload (tests)

    /// Builds the programs of Settings::backend in context `c` (made current, then released).
    LevelDevice(std::unique_ptr<EglContext> c, const Settings& s, const GlBackendOptions& options);
    ~LevelDevice();
    LevelDevice(const LevelDevice&) = delete;
    LevelDevice& operator=(const LevelDevice&) = delete;

    /// `count` invocations in dispatches of at most GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] groups each (at least one
    /// where count > 0) of the current program, which reads its first invocation's index from uniform
    /// `baseLocation` (left at 0 after). Returns the dispatches (build.comp's passes over records are indirect).
    std::size_t dispatchAll(std::size_t count, GLint baseLocation) const;

    /// One pass over the iteration's records (their count and the arguments are on the device).
    void draw(int pass, LevelStats& level, Stats& stats) const;

    /// The uniforms that stay the same over a level's iterations, in the programs of an iteration (each
    /// iteration sets only its index: its view is views[iteration] on the device).
    void setLevelUniforms(double coordinateBound) const;

    /// Sends what the record build and the iterations need of the level's items (their primitives and owners) and the
    /// first view, clears their boxes (built by buildRecords) and the chain, and sets the alive set: every item alive.
    /// A level described by its objects sends its ranges instead, and start.comp writes all of that on the device
    /// (startItems).
    void uploadItems(const LevelItems& items, const LevelStart& start, LevelStats& level, Stats& stats);

    /// Sends the upload's positions (those before the mapped meshes') and what changed of the mapped meshes' own
    /// vertices, then maps those to the positions after them (map.comp, their transforms sent).
    void uploadPositions(const GpuGeometry& geometry, Stats& stats);
    /// Sends the boxes that changed since the last upload and builds the others from the positions
    /// (group_boxes.comp, after uploadPositions), their ranges sent where they changed.
    void uploadBoxes(const GpuGeometry& geometry, Stats& stats);
    /// GlBackendOptions::positionsAfterUpload and boxesAfterUpload: the first `floats` of `buffer` read back into `to`
    /// (tests only; nothing where `to` is null).
    void readForTests(Buffer buffer, std::size_t floats, std::vector<float>* to) const;

    /// A level described by its objects: its ranges and partner boxes sent as one buffer (kRanges), and (inheriting)
    /// the last level's alive set copied aside on the device.
    void sendRanges(const LevelItems& items, Stats& stats);
    /// start.comp over a level described by its objects: its items' primitives, owners and start, and the first
    /// view (nothing read back).
    void startItems(const LevelItems& items, double coordinateBound, LevelStats& level, Stats& stats);
    /// Throws BackendError where a level's exact request (LevelItems::exact) names ranges it does not have, or
    /// partners beyond its chunks.
    void checkExactRequest(const LevelItems& items) const;
    /// exact.comp after the level's iterations (their alive set): its pairs appended to kExact, whose word 0 counts
    /// the frame's (cleared first where `firstOfFrame`). Nothing is read back.
    void findExactPairs(const LevelItems& items, bool firstOfFrame, LevelStats& level, Stats& stats);
    /// The counters an iteration (and start.comp) gathers into, emptied.
    void clearIterationCounters() const;

    /// Binds the shader storage buffers every program reads and writes.
    void bindBuffers() const;

    /// One pass of build.comp over `invocations` invocations.
    void buildPass(int pass, std::size_t invocations, LevelStats& level, Stats& stats) const;

    /// Builds the records of the level's alive items for the view of iteration `iteration` on the device
    /// (build.comp; on the compute back-end each primitive is split into bands of its largest footprint over the three
    /// views; first the items' boxes when `withBounds`: at a level's start). One dispatch, or two where short bands
    /// have no estimate of their length (perBandEstimate). Its last work group writes the count and
    /// the indirect arguments of the next iteration's record-sized passes. Nothing is read back: the level's read-back
    /// brings the count, and a build that needed more records than the buffers hold is run again.
    void buildRecords(int iteration, bool withBounds, LevelStats& level, Stats& stats);

    /// Grows the record buffers to hold at least `records` records (and recordCapacity).
    void reserveRecords(std::size_t records);

    /// After a build that needed `needed` records (`approx`: the same summed in float) and found the buffers short:
    /// room for them and a quarter more, within the limit of one build.
    void growRecords(std::uint32_t needed, float approx);

    /// Opens a timer query span (unless one is open) / closes it.
    void startTiming();
    void endTiming();
    /// The device time of span `span`, opened at `opened`, once its work has been waited for (-1: none or implausible;
    /// recordGpuTime).
    double spanMs(std::size_t span, Clock::time_point opened) const;
    /// The last span opened (kNoSpan without timer queries or before any).
    std::size_t lastSpan() const { return hasTimers && spans > 0 ? spans - 1 : kNoSpan; }
    /// A frame starts (or its deferred levels were collected): the spans' queries may be used again.
    void forgetSpans();
    /// The uploads' spans (uploadSpans) into Stats::uploadGpuMs: after a blocking read-back, when their work is done.
    void noteUploadSpans(Stats& stats);

    /// Clears the images, the flags and the counters of one iteration and binds what every pass reads and writes.
    void prepareIteration(std::size_t itemCount);

    /// Issues iteration `iteration` of the level (nothing waits for it): the three passes over the alive items'
    /// records, whose last work group ends the iteration on the device (iteration.glsl: the stop rule, the next view
    /// and the next iteration's indirect arguments). On the compute back-end the nearest pass packs the records of
    /// the items alive (cull.comp), the second pass runs over those (second.comp) and the flag pass ends the iteration
    /// (flag.comp); on the raster back-end a set-up dispatch comes first and a survivor pass last, which packs and ends
    /// it (survive.comp). Where the chain stopped before it, every pass is dispatched with empty arguments: nothing
    /// runs.
    void issueIteration(int iteration, LevelStats& level, Stats& stats);
    /// The packed records become the ones the passes read (kPrims and kPrimsNext swap, bound again).
    void swapRecords();
    /// Makes program `p` current for iteration `iteration`'s pass (its view is views[iteration]).
    void useForIteration(GLuint p, int iteration) const;

    /// Reads `bytes` at `offset` of `buffer` back into `to`: blocks until the device has finished the work submitted
    /// before, which the level's waitMs counts (with the tests' readBackDelayMs inside it). With `until`, the wait
    /// ends there at the latest (a fence polled): false, nothing read, where the device had not finished by then.
    bool readBack(GLuint buffer, std::size_t offset, std::size_t bytes, void* to, LevelStats& level, Stats& stats,
                  const Deadline& until = Deadline());

    /// Waits for the iterations issued: one read-back of the counters, the chain (and that of a level run ahead) and
    /// the alive set.
    void waitForChain(bool withAhead, LevelStats& level, Stats& stats);

    /// Issues the level: its items sent, its records built and `iterations` iterations (at least 1, at most
    /// Settings::maxIterations). `perBand`: short bands' pixels per band estimated from the last build in the level's
    /// place (CULLIDE_CHAIN_PER_BAND; 0: none, its builds sum the footprints first). Returns how many were issued.
    int issueLevel(const LevelItems& items, const LevelStart& start, int iterations, float perBand, LevelStats& level,
                   Stats& stats);

    /// The alive set as 0/1 per item, from the level's read-back (every item pruned where one owner is left).
    void readSurvivors(std::uint32_t stop, std::vector<std::uint8_t>& survivors) const;

    /// The iterations as they ran on the device, from ViewRecord `first` of `views` on (tests only: a read-back that no
    /// stat counts).
    static void readTrace(GLuint views, std::size_t first, int ran, std::vector<IterationTrace>& trace);
};

}  // namespace cullide::gl
