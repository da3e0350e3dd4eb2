#include "gl/VisibilityPass.h"

#include "bindings.h"
#include "gl/EglContext.h"
#include "gl/GlApi.h"
#include "gl/GlBuffers.h"
#include "gl/GpuTimes.h"
#include "gl/GlProgram.h"
#include "gl/ViewRecords.h"
#include "CullerBackends.h"
#include "VisibilityLevel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <initializer_list>
#include <string>
#include <thread>

namespace cullide::gl {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Records of one build beyond which the level gives up (BackendError: that frame prunes nothing): 64 Mi records,
/// 1 GiB of device memory. A build makes about (primitives + max(CULLIDE_TARGET_INVOCATIONS, footprint pixels /
/// CULLIDE_PIXELS_PER_INVOCATION)) records on a hardware GPU, primitives + footprint pixels / 4,096 on llvmpipe.
constexpr double kMaxRecords = 67108864.0;

/// Work groups of primitives (64 each) beyond which a level gives up (BackendError, as above): 16.7 M primitives.
/// build.comp's single-group passes loop over the work groups, about 13 iterations per 64 of them, and llvmpipe
/// silently ends a shader's loops after 65,535 iterations.
constexpr std::size_t kMaxBuildGroups = 262144;

enum Buffer {
    kPositions,
    kIndices,
    kBoxes,
    kPrims,
    kPrimsNext,  ///< survive.comp's packed records; swapped with kPrims after every iteration
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
    kParent,
    kParentAlive,
    kStash,       ///< a level run ahead: words CULLIDE_DISPATCH_RECORDS .. CULLIDE_AHEAD of its counters
    kStashViews,  ///< ... and its views (where a trace is asked for)
    kBufferCount
};
constexpr std::size_t kRecordBytes = 7 * 16;  // PrimRecord in common.glsl

/// Words of the counter buffer for a level of `items` items: counters, dispatch block, chain, the chain of a level
/// run ahead and a bit per item.
std::size_t counterWords(std::size_t items) { return CULLIDE_ALIVE_BITS + (items + 31) / 32; }

/// The words of a level's chain that a level run ahead keeps (kStash) until the next level's read-back.
constexpr std::size_t kChainWords = CULLIDE_AHEAD - CULLIDE_DISPATCH_RECORDS;

/// A level's chain as read back: word w of its counter buffer (CULLIDE_DISPATCH_RECORDS <= w < CULLIDE_AHEAD).
struct Chain {
    const std::uint32_t* words;  ///< word CULLIDE_DISPATCH_RECORDS
    std::uint32_t operator[](int w) const { return words[w - CULLIDE_DISPATCH_RECORDS]; }
    int ran() const { return static_cast<int>((*this)[CULLIDE_CHAIN_RAN]); }
    std::uint32_t stop() const { return (*this)[CULLIDE_CHAIN_STOP]; }
};

/// A level run ahead (pruneLevelAhead) whose chain has not been read back yet.
struct AheadLevel {
    std::size_t levelIndex = 0;  ///< into Stats::levels
    std::size_t place = 0;
    int issued = 0;
    std::vector<IterationTrace>* trace = nullptr;
};

}  // namespace

struct VisibilityPass::Impl {
    std::unique_ptr<EglContext> ownContext;
    EglContext& context;
    Settings settings;
    GLuint program = 0;
    GLuint setupProgram = 0;  // raster back-end only
    GLuint surviveProgram = 0;
    GLuint buildProgram = 0;
    int bands = CULLIDE_BANDS_NONE;  ///< build.comp's CULLIDE_BANDS_* for this back-end and device
    GLuint vao = 0;
    GLuint framebuffer = 0;
    GLuint images[4] = {};
    GLuint buffers[kBufferCount] = {};
    std::size_t capacity[kBufferCount] = {};
    std::size_t valid[kBufferCount] = {};  ///< bytes of the buffer that hold the last upload (positions, indices)
    GLuint timer = 0;
    std::size_t maxGroups = 65535;  ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    std::vector<std::uint32_t> readScratch;  ///< a level's read-back: counters, dispatch block, chain, alive bits
    const GpuGeometry* geometry = nullptr;
    const LevelItems* levelItems = nullptr;  ///< the level being pruned
    /// Per place of a frame (LevelStart::place): how many iterations a level there issues before its read-back, the
    /// most the levels there ran over the last frames (a level whose count goes up and down then never waits twice:
    /// the iterations issued past the end of its chain cost empty dispatches, a second read-back a round trip).
    struct PlaceHistory {
        int guess = 0;       ///< 0: nothing ran there yet (all that are allowed)
        int sinceGuess = 0;  ///< levels there since one ran `guess` iterations
        bool wait = false;   ///< the level run ahead there stopped early: waited for until it runs as one chain
    };
    std::vector<PlaceHistory> places;
    std::unique_ptr<AheadLevel> ahead;  ///< a level run ahead, not read back yet
    std::size_t lastItemCount = 0;       ///< of the last level (what the next level's items may inherit)
    /// Records the record buffers (kPrims, kPrimsNext; kRecords on the raster back-end) hold: kept between levels and
    /// frames, grown when a build needs more (the iteration then runs again).
    std::size_t recordCapacity = 0;
    /// The open timer query's span: from the first pass after the last read-back to the next read-back.
    bool timing = false;
    Clock::time_point timedSpan;
    double readBackDelayMs = 0.0;  ///< GlBackendOptions::readBackDelayMs (tests: a slow device's round trip)

    Impl(std::unique_ptr<EglContext> c, const Settings& s, const GlBackendOptions& options)
        : ownContext(std::move(c)), context(*ownContext), settings(s), readBackDelayMs(options.readBackDelayMs) {
        context.makeCurrent();
        if (settings.backend == Backend::Compute) {
            program = linkProgram(
                {compileShader(GL_COMPUTE_SHADER, {"view.glsl", "common.glsl", "visit.glsl", "cull.comp"})},
                                  "the visibility program");
        } else {
            setupProgram = linkProgram(
                {compileShader(GL_COMPUTE_SHADER, {"view.glsl", "common.glsl", "records.glsl", "cull_setup.comp"})},
                "the visibility setup program");
            GLuint vs = compileShader(GL_VERTEX_SHADER, {"view.glsl", "common.glsl", "records.glsl", "cull.vert"});
            GLuint fs = 0;
            try {
                fs = compileShader(GL_FRAGMENT_SHADER,
                                   {"view.glsl", "common.glsl", "visit.glsl", "records.glsl", "cull.frag"});
            } catch (...) {
                glDeleteShader(vs);
                throw;
            }
            program = linkProgram({vs, fs}, "the visibility raster program");
        }
        surviveProgram =
            linkProgram({compileShader(GL_COMPUTE_SHADER, {"view.glsl", "survive.comp"})}, "the survivor program");
        buildProgram =
            linkProgram({compileShader(GL_COMPUTE_SHADER, {"view.glsl", "build.comp"})}, "the record build program");
        if (settings.backend == Backend::Compute)
            bands = context.isSoftware() && !options.shortBands ? CULLIDE_BANDS_LONG : CULLIDE_BANDS_SHORT;
        glCreateVertexArrays(1, &vao);
        glCreateBuffers(kBufferCount, buffers);
        const GLsizei width = 3 * settings.resolution;
        const GLsizei height = settings.resolution;
        glCreateTextures(GL_TEXTURE_2D, 4, images);
        for (GLuint image : images) glTextureStorage2D(image, 1, GL_R32UI, width, height);
        glCreateFramebuffers(1, &framebuffer);
        glNamedFramebufferParameteri(framebuffer, GL_FRAMEBUFFER_DEFAULT_WIDTH, width);
        glNamedFramebufferParameteri(framebuffer, GL_FRAMEBUFFER_DEFAULT_HEIGHT, height);
        if (context.hasTimerQueries()) glGenQueries(1, &timer);
        GLint limit = 65535;
        glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &limit);
        maxGroups = static_cast<std::size_t>(std::max(1, limit));
        reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * CULLIDE_ALIVE_BITS);
        reserveBuffer(buffers[kViews], capacity[kViews], sizeof(ViewRecord) * (CULLIDE_MAX_ITERATIONS + 1));
        for (Buffer b : {kParent, kParentAlive, kStash, kStashViews}) reserveBuffer(buffers[b], capacity[b], 4);
        checkGlError("creating the visibility pass");
        // Every call makes the context current on its own thread: the culler may be used from another thread than
        // the one that made it (the Bullet adapter makes Culling::Auto's culler off the step's thread).
        context.release();
    }

    ~Impl() {
        if (!context.tryMakeCurrent()) return;  // the context is gone: so are its objects
        if (timer) glDeleteQueries(1, &timer);
        glDeleteFramebuffers(1, &framebuffer);
        glDeleteTextures(4, images);
        glDeleteBuffers(kBufferCount, buffers);
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(program);
        if (setupProgram) glDeleteProgram(setupProgram);
        glDeleteProgram(surviveProgram);
        glDeleteProgram(buildProgram);
    }

    /// `count` invocations in dispatches of at most GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] groups each; the program
    /// reads its first index from CULLIDE_LOC_PRIM_BASE (build.comp: the passes over records are indirect).
    void dispatchAll(std::size_t count) const {
        const std::size_t groups = (count + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
        for (std::size_t first = 0; first < groups; first += maxGroups) {
            glUniform1ui(CULLIDE_LOC_PRIM_BASE, static_cast<GLuint>(first * CULLIDE_COMPUTE_GROUP_SIZE));
            glDispatchCompute(static_cast<GLuint>(std::min<std::size_t>(maxGroups, groups - first)), 1, 1);
        }
        glUniform1ui(CULLIDE_LOC_PRIM_BASE, 0);
    }

    /// One pass over the iteration's records (their count and the arguments are on the device).
    void draw(int pass, LevelStats& level, Stats& stats) const {
        glUniform1i(CULLIDE_LOC_PASS, pass);
        if (settings.backend == Backend::Compute) {
            glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_CULL);
        } else {
            const ThirdPartyLeakScope ignoreMesaDrawLeak;
            // 3 views x the records, a triangle each
            const std::uintptr_t offset = 4 * CULLIDE_DISPATCH_DRAW;
            glDrawArraysIndirect(GL_TRIANGLES, reinterpret_cast<const void*>(offset));
        }
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        level.draws += 1;
        stats.draws += 1;
    }

    void setUniforms(int iteration) const {
        glUniform1i(CULLIDE_LOC_RESOLUTION, settings.resolution);
        glUniform1ui(CULLIDE_LOC_ITERATION, static_cast<GLuint>(iteration));
        glUniform1i(CULLIDE_LOC_CONSERVATIVE, settings.mode == Mode::Reliable ? 1 : 0);
        glUniform1ui(CULLIDE_LOC_AXES, settings.axes);
    }

    /// Sends what the record build and the survivor pass need of the level's items (their primitives and owners) and
    /// the first view; clears their boxes (built by buildRecords) and the chain, and sets the alive set (every item
    /// alive).
    void uploadItems(const LevelItems& items, const LevelStart& start, LevelStats& level, Stats& stats) {
        const std::size_t n = items.size();
        const bool inherits = !items.parentBegin.empty();
        const auto send = Clock::now();
        if (inherits) {  // the last level's alive set, before this level's replaces it
            reserveBuffer(buffers[kParentAlive], capacity[kParentAlive], lastItemCount * 4);
            glCopyNamedBufferSubData(buffers[kAlive], buffers[kParentAlive], 0, 0,
                                     static_cast<GLsizeiptr>(lastItemCount * 4));
            uploadBuffer(buffers[kParent], capacity[kParent], items.parentBegin.data(), items.parentBegin.size() * 4);
            stats.bytesUploaded += items.parentBegin.size() * 4;
        }
        lastItemCount = n;
        uploadBuffer(buffers[kOwners], capacity[kOwners], items.owner.data(), n * 4);
        uploadBuffer(buffers[kPrimBegin], capacity[kPrimBegin], items.primBegin.data(), items.primBegin.size() * 4);
        uploadBuffer(buffers[kItemPrims], capacity[kItemPrims], items.prims.data(), items.prims.size() * 4);
        const ViewRecord first = toViewRecord(start.view, start.idBits);
        glNamedBufferSubData(buffers[kViews], 0, sizeof first, &first);
        stats.bytesUploaded += (n + items.primBegin.size() + items.prims.size()) * 4 + sizeof first;
        reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * counterWords(n));
        // Every item alive, or (inheriting) none until build.comp's first pass marks those whose parent survived.
        const GLuint zero = 0, startAlive = inherits ? 0u : static_cast<GLuint>(n);
        const GLuint aliveWord = inherits ? 0u : 0xFFFFFFFFu, aliveItem = inherits ? 0u : 1u;
        glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_CHAIN_RAN,
                                  4 * (CULLIDE_ALIVE_BITS - CULLIDE_CHAIN_RAN), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
        glNamedBufferSubData(buffers[kCounters], 4 * CULLIDE_CHAIN_ALIVE_START, 4, &startAlive);
        glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_ALIVE_BITS,
                                  static_cast<GLsizeiptr>(4 * (counterWords(n) - CULLIDE_ALIVE_BITS)), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &aliveWord);
        reserveBuffer(buffers[kFlags], capacity[kFlags], n * 4);
        reserveBuffer(buffers[kAlive], capacity[kAlive], n * 4);
        reserveBuffer(buffers[kItemBounds], capacity[kItemBounds], n * 24);
        const GLuint empty[2] = {0xFFFFFFFFu, 0u};
        glClearNamedBufferSubData(buffers[kAlive], GL_R32UI, 0, static_cast<GLsizeiptr>(n * 4), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &aliveItem);
        glClearNamedBufferSubData(buffers[kItemBounds], GL_R32UI, 0, static_cast<GLsizeiptr>(n * 12), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &empty[0]);
        glClearNamedBufferSubData(buffers[kItemBounds], GL_R32UI, static_cast<GLintptr>(n * 12),
                                  static_cast<GLsizeiptr>(n * 12), GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
        level.setupSendMs += msSince(send);
    }

    /// Binds the shader storage buffers every program reads and writes.
    void bindBuffers() const {
        const std::pair<GLuint, Buffer> bindings[] = {
            {CULLIDE_SSBO_POSITIONS, kPositions},   {CULLIDE_SSBO_INDICES, kIndices},
            {CULLIDE_SSBO_BOXES, kBoxes},           {CULLIDE_SSBO_PRIMS, kPrims},
            {CULLIDE_SSBO_ITEM_OWNER, kOwners},     {CULLIDE_SSBO_FLAGS, kFlags},
            {CULLIDE_SSBO_COUNTERS, kCounters},     {CULLIDE_SSBO_ALIVE, kAlive},
            {CULLIDE_SSBO_ITEM_BOUNDS, kItemBounds}, {CULLIDE_SSBO_PRIM_BEGIN, kPrimBegin},
            {CULLIDE_SSBO_ITEM_PRIMS, kItemPrims},  {CULLIDE_SSBO_BANDS, kBands},
            {CULLIDE_SSBO_BUILD, kBuild},           {CULLIDE_SSBO_VIEWS, kViews},
            {CULLIDE_SSBO_PARENT, kParent},         {CULLIDE_SSBO_PARENT_ALIVE, kParentAlive}};
        for (const auto& [binding, buffer] : bindings)
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffers[buffer]);
    }

    /// One pass of build.comp over `invocations` invocations.
    void buildPass(int pass, std::size_t invocations, LevelStats& level, Stats& stats) const {
        glUniform1i(CULLIDE_LOC_PASS, pass);
        dispatchAll(invocations);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        level.draws += 1;
        stats.draws += 1;
    }

    /// Builds the records of the level's alive items for the view of iteration `iteration` on the device
    /// (build.comp; on the compute back-end each primitive is split into bands of its largest footprint over the three
    /// views; first the items' boxes when `withBounds`: at a level's start). Its last work group writes the count and
    /// the indirect arguments of the next iteration's record-sized passes. Nothing is read back: the level's read-back
    /// brings the count, and a build that needed more records than the buffers hold is run again.
    void buildRecords(int iteration, bool withBounds, LevelStats& level, Stats& stats) {
        const std::size_t primCount = levelItems->prims.size();
        const std::size_t groups = (primCount + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
        if (groups > kMaxBuildGroups)
            throw BackendError("a level of " + std::to_string(primCount) + " primitives is over the limit of " +
                               std::to_string(kMaxBuildGroups * CULLIDE_COMPUTE_GROUP_SIZE));
        const auto setUp = Clock::now();
        reserveRecords(primCount);
        reserveBuffer(buffers[kBands], capacity[kBands], primCount * 4);
        reserveBuffer(buffers[kBuild], capacity[kBuild], (CULLIDE_BUILD_GROUPS + groups) * 4);
        // The build's atomic counters start at 0 (the dispatch block is rewritten by the build's last work group).
        const GLuint zero = 0;
        glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_DISPATCH_NEEDED,
                                  4 * (CULLIDE_COUNTERS_SIZE - CULLIDE_DISPATCH_NEEDED), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &zero);
        glClearNamedBufferSubData(buffers[kBuild], GL_R32UI, 4 * CULLIDE_BUILD_FOOTPRINTS_DONE, 4, GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &zero);
        bindBuffers();
        glUseProgram(buildProgram);
        glUniform1ui(CULLIDE_LOC_ITERATION, static_cast<GLuint>(iteration));
        glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(levelItems->size()));
        glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(primCount));
        glUniform1i(CULLIDE_LOC_BANDS, bands);
        glUniform1ui(CULLIDE_LOC_GROUPS, static_cast<GLuint>(groups));
        glUniform1ui(CULLIDE_LOC_CAPACITY, static_cast<GLuint>(recordCapacity));
        glUniform1ui(CULLIDE_LOC_MAX_GROUPS, static_cast<GLuint>(maxGroups));
        glUniform1i(CULLIDE_LOC_WITH_BOUNDS, withBounds ? 1 : 0);
        const std::size_t parents = levelItems->parentBegin.empty() ? 0 : levelItems->parentBegin.size() - 1;
        glUniform1ui(CULLIDE_LOC_PARENTS, static_cast<GLuint>(parents));
        startTiming();
        if (withBounds && bands == CULLIDE_BANDS_NONE) buildPass(CULLIDE_BUILD_PASS_BOUNDS, primCount, level, stats);
        if (bands != CULLIDE_BANDS_NONE) buildPass(CULLIDE_BUILD_PASS_FOOTPRINTS, primCount, level, stats);
        buildPass(CULLIDE_BUILD_PASS_APPEND, primCount, level, stats);
        checkGlError("building a level's records");
        level.recordBuilds += 1;
        level.setupMs += msSince(setUp);
    }

    /// Grows the record buffers to hold at least `records` records (and recordCapacity).
    void reserveRecords(std::size_t records) {
        recordCapacity = std::max<std::size_t>({recordCapacity, records, 64});
        reserveBuffer(buffers[kPrims], capacity[kPrims], recordCapacity * 16);
        reserveBuffer(buffers[kPrimsNext], capacity[kPrimsNext], recordCapacity * 16);
        if (settings.backend == Backend::Raster)
            reserveBuffer(buffers[kRecords], capacity[kRecords], 3 * recordCapacity * kRecordBytes);
    }

    /// After a build that needed `needed` records (`approx`: the same summed in float) and found the buffers short:
    /// room for them and a quarter more, within the limit of one build.
    void growRecords(std::uint32_t needed, float approx) {
        if (!(approx <= kMaxRecords))  // also NaN
            throw BackendError("a level needs about " + std::to_string(approx) + " records, over the limit of " +
                               std::to_string(static_cast<std::size_t>(kMaxRecords)));
        const double want = std::max<double>(needed, approx) * 1.25 + 64.0;
        recordCapacity = static_cast<std::size_t>(std::min(want, kMaxRecords));
    }

    void startTiming() {
        if (timing) return;
        timing = true;
        timedSpan = Clock::now();
        if (timer) glBeginQuery(GL_TIME_ELAPSED, timer);
    }

    void endTiming() {
        if (!timing) return;
        if (timer) glEndQuery(GL_TIME_ELAPSED);
        timing = false;
    }

    /// Clears the images, the flags and the counters of one iteration and binds what every pass reads and writes.
    void prepareIteration(std::size_t itemCount) {
        const GLuint empty[2] = {0xFFFFFFFFu, 0u};
        glClearTexImage(images[CULLIDE_IMAGE_NEAR1], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[0]);
        glClearTexImage(images[CULLIDE_IMAGE_NEAR2], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[0]);
        glClearTexImage(images[CULLIDE_IMAGE_FAR1], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
        glClearTexImage(images[CULLIDE_IMAGE_FAR2], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
        glClearNamedBufferSubData(buffers[kFlags], GL_R32UI, 0, static_cast<GLsizeiptr>(itemCount * 4),
                                  GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
        GLuint counters[CULLIDE_COUNTER_COUNT] = {};
        counters[CULLIDE_COUNTER_OWNER_MIN] = 0xFFFFFFFFu;
        for (int a = 0; a < 3; ++a) counters[CULLIDE_COUNTER_LO + a] = 0xFFFFFFFFu;
        glNamedBufferSubData(buffers[kCounters], 0, sizeof counters, counters);
        for (GLuint unit = 0; unit < 4; ++unit)
            glBindImageTexture(unit, images[unit], 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
        bindBuffers();
        glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, buffers[kCounters]);
        glBindBuffer(GL_DRAW_INDIRECT_BUFFER, buffers[kCounters]);
        glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        glViewport(0, 0, 3 * settings.resolution, settings.resolution);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glBindVertexArray(vao);
    }

    /// Issues iteration `iteration` of the level (nothing waits for it): the three passes over the alive items'
    /// records and the survivor pass, which packs the records of the items still alive and whose last work group
    /// ends the iteration on the device (survive.comp: the stop rule, the next view and the next iteration's indirect
    /// arguments). Where the chain stopped before it, every pass is dispatched with empty arguments: nothing runs.
    void issueIteration(int iteration, double coordinateBound, LevelStats& level, Stats& stats) {
        const std::size_t itemCount = levelItems->size();
        startTiming();
        prepareIteration(itemCount);
        if (settings.backend == Backend::Raster) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_RECORDS, buffers[kRecords]);
            glUseProgram(setupProgram);
            setUniforms(iteration);
            glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_CULL);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            level.draws += 1;
            stats.draws += 1;
        }
        glUseProgram(program);
        setUniforms(iteration);
        draw(CULLIDE_PASS_NEAREST, level, stats);
        draw(CULLIDE_PASS_SECOND, level, stats);
        draw(CULLIDE_PASS_FLAG, level, stats);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_PRIMS_OUT, buffers[kPrimsNext]);
        glUseProgram(surviveProgram);
        glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(itemCount));
        glUniform1ui(CULLIDE_LOC_REQUIRED, requiredFlags(settings.axes));
        glUniform1ui(CULLIDE_LOC_ITERATION, static_cast<GLuint>(iteration));
        glUniform1ui(CULLIDE_LOC_MAX_ITERATIONS, static_cast<GLuint>(settings.maxIterations));
        glUniform1ui(CULLIDE_LOC_MAX_GROUPS, static_cast<GLuint>(maxGroups));
        glUniform1i(CULLIDE_LOC_RESOLUTION, settings.resolution);
        glUniform1d(CULLIDE_LOC_MARGIN, settings.margin);
        glUniform1d(CULLIDE_LOC_COORDINATE_BOUND, coordinateBound);
        glUniform1d(CULLIDE_LOC_MIN_PRUNE_FRACTION, settings.minPruneFraction);
        glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_SURVIVE);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        level.draws += 1;
        stats.draws += 1;
        // The records the survivor pass packed are the next iteration's.
        std::swap(buffers[kPrims], buffers[kPrimsNext]);
        std::swap(capacity[kPrims], capacity[kPrimsNext]);
    }

    /// Reads `bytes` at `offset` of `buffer` back into `to`: blocks until the device has finished the work submitted
    /// before, which the level's waitMs counts (with the tests' readBackDelayMs inside it).
    void readBack(GLuint buffer, std::size_t offset, std::size_t bytes, void* to, LevelStats& level, Stats& stats) {
        const auto waitStart = Clock::now();
        glGetNamedBufferSubData(buffer, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(bytes), to);
        if (readBackDelayMs > 0.0)
            std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(readBackDelayMs));
        level.waitMs += msSince(waitStart);
        level.blockingReadBacks += 1;
        stats.blockingReadBacks += 1;
        stats.bytesReadBack += bytes;
    }

    /// Waits for the iterations issued: one read-back of the counters, the chain (and that of a level run ahead) and
    /// the alive set.
    void waitForChain(LevelStats& level, Stats& stats) {
        const std::size_t words = counterWords(levelItems->size());
        endTiming();
        if (ahead)
            glCopyNamedBufferSubData(buffers[kStash], buffers[kCounters], 0, 4 * CULLIDE_AHEAD, 4 * kChainWords);
        readScratch.resize(words);
        readBack(buffers[kCounters], 0, 4 * words, readScratch.data(), level, stats);
        recordGpuTime(timer ? timerResultMs(timer, msSince(timedSpan)) : -1.0, level, stats);
        checkGlError("a level's visibility iterations");
    }

    /// Issues the level: its items sent, its records built and the iterations the last level in its place ran (all
    /// that are allowed the first time). Returns how many were issued.
    int issueLevel(const LevelItems& items, const LevelStart& start, LevelStats& level, Stats& stats) {
        endTiming();  // a level abandoned by an error
        levelItems = &items;
        const auto send = Clock::now();
        uploadItems(items, start, level, stats);
        level.setupMs += msSince(send);
        buildRecords(0, true, level, stats);
        const int issued = std::min(settings.maxIterations, std::max(guessFor(start.place), 1));
        for (int i = 0; i < issued; ++i) issueIteration(i, start.coordinateBound, level, stats);
        return issued;
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
        int issued = issueLevel(items, start, level, stats);
        int next = 0;  // the first iteration of the chain being waited for
        bool built = true;
        bool oneChain = true;
        int shortBuilds = 0;
        for (;;) {
            waitForChain(level, stats);
            if (ahead) finishAhead(stats, true);
            const Chain chain{readScratch.data() + CULLIDE_DISPATCH_RECORDS};
            const int ran = chain.ran();
            if (ran <= next || ran > issued) throw BackendError("the device's chain of iterations did not run");
            level.idleIterations += static_cast<std::size_t>(issued - ran);
            next = ran;
            if (chain[CULLIDE_DISPATCH_SHORT] != 0) {  // iteration ran - 1 pruned nothing: build again, rerun it
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
                if (chain.stop() == CULLIDE_STOP_DONE || chain.stop() == CULLIDE_STOP_ONE_OWNER ||
                    ran == maxIterations)
                    break;
            }
            oneChain = false;
            // Records for the next view (a refit) or again (short); the chain goes on from `next`: to the end where
            // the batch was too short.
            if (chain[CULLIDE_DISPATCH_SHORT] != 0 || chain.stop() == CULLIDE_STOP_REFIT) {
                buildRecords(next, false, level, stats);  // the items' boxes are built already
                built = true;
            }
            const int guess = std::max(guessFor(start.place), next + 1);
            issued = chain.stop() == CULLIDE_STOP_NONE ? maxIterations : std::min(maxIterations, guess);
            for (int i = next; i < issued; ++i) issueIteration(i, start.coordinateBound, level, stats);
        }
        const Chain chain{readScratch.data() + CULLIDE_DISPATCH_RECORDS};
        remember(start.place, chain.ran(), oneChain);
        noteIterations(chain, items.size(), level);
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
        const int issued = issueLevel(items, start, level, stats);
        reserveBuffer(buffers[kStash], capacity[kStash], 4 * kChainWords);
        glCopyNamedBufferSubData(buffers[kCounters], buffers[kStash], 4 * CULLIDE_DISPATCH_RECORDS, 0,
                                 4 * kChainWords);
        if (trace) {
            const std::size_t bytes = sizeof(ViewRecord) * static_cast<std::size_t>(issued);
            reserveBuffer(buffers[kStashViews], capacity[kStashViews], bytes);
            glCopyNamedBufferSubData(buffers[kViews], buffers[kStashViews], 0, 0, static_cast<GLsizeiptr>(bytes));
        }
        endTiming();  // its device time is in the next level's span
        ahead = std::make_unique<AheadLevel>(AheadLevel{levelIndex, start.place, issued, trace});
        checkGlError("a level run ahead");
    }

    /// The level run ahead, from the chain read back with the next level's (`inReadBack`) or on its own: its stats
    /// and trace. Where it stopped early (records to build again, more iterations needed) it is waited for next time
    /// and, when a level inherited its survivors, both run again (LevelsRerun).
    void finishAhead(Stats& stats, bool inReadBack) {
        const std::unique_ptr<AheadLevel> a = std::move(ahead);
        std::vector<std::uint32_t> own;
        const std::uint32_t* words = nullptr;
        if (inReadBack) {
            words = readScratch.data() + CULLIDE_AHEAD;
        } else {
            own.resize(kChainWords);
            readBack(buffers[kStash], 0, 4 * kChainWords, own.data(), stats.levels[a->levelIndex], stats);
            words = own.data();
        }
        const Chain chain{words};
        LevelStats& level = stats.levels[a->levelIndex];
        const int ran = chain.ran();
        if (ran < 1 || ran > a->issued) throw BackendError("the device's chain of iterations did not run");
        const bool early = chain[CULLIDE_DISPATCH_SHORT] != 0 || chain.stop() == CULLIDE_STOP_REFIT ||
                           (chain.stop() == CULLIDE_STOP_NONE && ran < settings.maxIterations);
        level.idleIterations += static_cast<std::size_t>(a->issued - ran);
        if (chain[CULLIDE_DISPATCH_SHORT] != 0) level.shortBuilds += 1;
        else level.records += chain[CULLIDE_DISPATCH_NEEDED];
        if (early) {  // how many it needs is not known: waited for next time, which finds out
            if (a->place >= places.size()) places.resize(a->place + 1);
            places[a->place].wait = true;
        } else {
            remember(a->place, ran, true);
        }
        noteIterations(chain, std::size_t{chain[CULLIDE_CHAIN_ALIVE_START]}, level);
        if (a->trace) readTrace(buffers[kStashViews], ran, *a->trace);
        if (early && inReadBack) throw LevelsRerun{};
    }

    /// The level's iterations into its stats, from the chain's items alive at its start and after each iteration.
    static void noteIterations(const Chain& chain, std::size_t aliveAtStart, LevelStats& level) {
        std::size_t before = aliveAtStart;
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

    /// The alive set as 0/1 per item, from the level's read-back (every item pruned where one owner is left).
    void readSurvivors(std::uint32_t stop, std::vector<std::uint8_t>& survivors) const {
        const std::size_t n = levelItems->size();
        const std::uint32_t* bits = readScratch.data() + CULLIDE_ALIVE_BITS;
        survivors.resize(n);
        const bool allPruned = stop == CULLIDE_STOP_ONE_OWNER;
        for (std::size_t i = 0; i < n; ++i)
            survivors[i] = allPruned ? 0 : static_cast<std::uint8_t>((bits[i / 32] >> (i % 32)) & 1u);
    }

    /// The iterations as they ran on the device (tests only: a read-back that no stat counts).
    static void readTrace(GLuint views, int ran, std::vector<IterationTrace>& trace) {
        std::vector<ViewRecord> records(static_cast<std::size_t>(ran));
        glGetNamedBufferSubData(views, 0, static_cast<GLsizeiptr>(records.size() * sizeof(ViewRecord)),
                                records.data());
        for (const ViewRecord& r : records) trace.push_back(toTrace(r));
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
    stats.bytesUploaded += uploadAfterPrefix(s.buffers[kPositions], s.capacity[kPositions], s.valid[kPositions],
                                             geometry.positions.data(), geometry.positions.size() * 4,
                                             geometry.keptPositions * 4);
    stats.bytesUploaded += uploadAfterPrefix(s.buffers[kIndices], s.capacity[kIndices], s.valid[kIndices],
                                             geometry.indices.data(), geometry.indices.size() * 4,
                                             geometry.keptIndices * 4);
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
