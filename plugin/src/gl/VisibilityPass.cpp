#include "gl/VisibilityPass.h"

#include "bindings.h"
#include "gl/EglContext.h"
#include "gl/GlApi.h"
#include "gl/GlBuffers.h"
#include "gl/GpuTimes.h"
#include "gl/GlProgram.h"
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
    kBufferCount
};
constexpr std::size_t kRecordBytes = 7 * 16;  // PrimRecord in common.glsl

/// Words of the counter buffer for a level of `items` items: counters, dispatch block and a bit per item.
std::size_t counterWords(std::size_t items) { return CULLIDE_ALIVE_BITS + (items + 31) / 32; }

/// Inverse of survive.comp's orderedBits.
float fromOrderedBits(std::uint32_t key) {
    const std::uint32_t bits = (key & 0x80000000u) != 0 ? (key & 0x7FFFFFFFu) : ~key;
    float f = 0.0f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
}

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
    std::vector<std::uint32_t> readScratch;  ///< an iteration's read-back: counters, dispatch block, alive bits
    std::vector<std::uint32_t> aliveBits;    ///< the alive set after the level's last iteration, a bit per item
    const GpuGeometry* geometry = nullptr;
    // The level being pruned (beginLevel .. its last iterate).
    const LevelItems* levelItems = nullptr;
    std::size_t recordCount = 0;  ///< records of the alive items, in kPrims (after an iteration that followed no build)
    bool dispatchFromBuild = false;  ///< the dispatch block is the last build's (buildRecords), not yet run over
    /// Records the record buffers (kPrims, kPrimsNext; kRecords on the raster back-end) hold: kept between levels and
    /// frames, grown when a build needs more (the iteration then runs again).
    std::size_t recordCapacity = 0;
    /// The open timer query's span: from the first pass after the last read-back (a record build's, or an
    /// iteration's) to the iteration's read-back.
    bool timing = false;
    Clock::time_point timedSpan;
    Aabb recordedView;            ///< the view the records' bands were fitted to
    double readBackDelayMs = 0.0;  ///< GlBackendOptions::readBackDelayMs (tests: a slow device's round trip)

    Impl(std::unique_ptr<EglContext> c, const Settings& s, const GlBackendOptions& options)
        : ownContext(std::move(c)), context(*ownContext), settings(s), readBackDelayMs(options.readBackDelayMs) {
        context.makeCurrent();
        if (settings.backend == Backend::Compute) {
            program = linkProgram({compileShader(GL_COMPUTE_SHADER, {"common.glsl", "visit.glsl", "cull.comp"})},
                                  "the visibility program");
        } else {
            setupProgram = linkProgram(
                {compileShader(GL_COMPUTE_SHADER, {"common.glsl", "records.glsl", "cull_setup.comp"})},
                "the visibility setup program");
            GLuint vs = compileShader(GL_VERTEX_SHADER, {"common.glsl", "records.glsl", "cull.vert"});
            GLuint fs = 0;
            try {
                fs = compileShader(GL_FRAGMENT_SHADER, {"common.glsl", "visit.glsl", "records.glsl", "cull.frag"});
            } catch (...) {
                glDeleteShader(vs);
                throw;
            }
            program = linkProgram({vs, fs}, "the visibility raster program");
        }
        surviveProgram = linkProgram({compileShader(GL_COMPUTE_SHADER, {"survive.comp"})}, "the survivor program");
        buildProgram = linkProgram({compileShader(GL_COMPUTE_SHADER, {"build.comp"})}, "the record build program");
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
        reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * CULLIDE_COUNTERS_SIZE);
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

    void setUniforms(std::uint32_t idBits, const View& view) const {
        glUniform1i(CULLIDE_LOC_RESOLUTION, settings.resolution);
        glUniform3fv(CULLIDE_LOC_VIEW_LO, 1, view.lo);
        glUniform3fv(CULLIDE_LOC_PIXEL_SCALE, 1, view.pixelScale);
        glUniform3fv(CULLIDE_LOC_DEPTH_SCALE, 1, view.depthScale);
        glUniform3fv(CULLIDE_LOC_HALF_SIZE, 1, view.halfSize);
        glUniform3fv(CULLIDE_LOC_DEPTH_PAD, 1, view.depthPad);
        glUniform1ui(CULLIDE_LOC_ID_BITS, idBits);
        glUniform1i(CULLIDE_LOC_CONSERVATIVE, settings.mode == Mode::Reliable ? 1 : 0);
        glUniform1ui(CULLIDE_LOC_AXES, settings.axes);
    }

    /// Sends what the record build and the survivor pass need of the level's items (their primitives and owners)
    /// and clears their boxes (built by buildRecords) and the alive set (every item alive).
    void uploadItems(const LevelItems& items, LevelStats& level, Stats& stats) {
        const std::size_t n = items.size();
        const auto send = Clock::now();
        uploadBuffer(buffers[kOwners], capacity[kOwners], items.owner.data(), n * 4);
        uploadBuffer(buffers[kPrimBegin], capacity[kPrimBegin], items.primBegin.data(), items.primBegin.size() * 4);
        uploadBuffer(buffers[kItemPrims], capacity[kItemPrims], items.prims.data(), items.prims.size() * 4);
        stats.bytesUploaded += (n + items.primBegin.size() + items.prims.size()) * 4;
        reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * counterWords(n));
        reserveBuffer(buffers[kFlags], capacity[kFlags], n * 4);
        reserveBuffer(buffers[kAlive], capacity[kAlive], n * 4);
        reserveBuffer(buffers[kItemBounds], capacity[kItemBounds], n * 24);
        const GLuint one = 1, empty[2] = {0xFFFFFFFFu, 0u};
        glClearNamedBufferSubData(buffers[kAlive], GL_R32UI, 0, static_cast<GLsizeiptr>(n * 4), GL_RED_INTEGER,
                                  GL_UNSIGNED_INT, &one);
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
            {CULLIDE_SSBO_BUILD, kBuild}};
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

    /// Builds the records of the level's alive items for `view` on the device (build.comp; on the compute back-end
    /// each primitive is split into bands of its largest footprint over the three views; first the items' boxes when
    /// `withBounds`: at a level's start). Its last work group writes the count and the indirect arguments of the next
    /// iteration's record-sized passes. Nothing is read back: the iteration's counters bring the count, and a build
    /// that needed more records than the buffers hold is run again.
    void buildRecords(const View& view, bool withBounds, LevelStats& level, Stats& stats) {
        const std::size_t primCount = levelItems->prims.size();
        const std::size_t groups = (primCount + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
        if (groups > kMaxBuildGroups)
            throw BackendError("a level of " + std::to_string(primCount) + " primitives is over the limit of " +
                               std::to_string(kMaxBuildGroups * CULLIDE_COMPUTE_GROUP_SIZE));
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
        glUniform3fv(CULLIDE_LOC_PIXEL_SCALE, 1, view.pixelScale);
        glUniform3fv(CULLIDE_LOC_HALF_SIZE, 1, view.halfSize);
        glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(levelItems->size()));
        glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(primCount));
        glUniform1i(CULLIDE_LOC_BANDS, bands);
        glUniform1ui(CULLIDE_LOC_GROUPS, static_cast<GLuint>(groups));
        glUniform1ui(CULLIDE_LOC_CAPACITY, static_cast<GLuint>(recordCapacity));
        glUniform1ui(CULLIDE_LOC_MAX_GROUPS, static_cast<GLuint>(maxGroups));
        glUniform1i(CULLIDE_LOC_WITH_BOUNDS, withBounds ? 1 : 0);
        startTiming();
        if (withBounds && bands == CULLIDE_BANDS_NONE) buildPass(CULLIDE_BUILD_PASS_BOUNDS, primCount, level, stats);
        if (bands != CULLIDE_BANDS_NONE) buildPass(CULLIDE_BUILD_PASS_FOOTPRINTS, primCount, level, stats);
        buildPass(CULLIDE_BUILD_PASS_APPEND, primCount, level, stats);
        checkGlError("building a level's records");
        dispatchFromBuild = true;
        level.recordBuilds += 1;
    }

    /// Grows the record buffers to hold at least `records` records (and recordCapacity).
    void reserveRecords(std::size_t records) {
        recordCapacity = std::max<std::size_t>({recordCapacity, records, 64});
        reserveBuffer(buffers[kPrims], capacity[kPrims], recordCapacity * 16);
        reserveBuffer(buffers[kPrimsNext], capacity[kPrimsNext], recordCapacity * 16);
        if (settings.backend == Backend::Raster)
            reserveBuffer(buffers[kRecords], capacity[kRecords], 3 * recordCapacity * kRecordBytes);
    }

    /// After an iteration whose build needed `needed` records (`approx`: the same summed in float) and found the
    /// buffers short: room for them and a quarter more, within the limit of one build.
    void growRecords(std::uint32_t needed, float approx) {
        if (!(approx <= kMaxRecords))  // also NaN
            throw BackendError("a level needs about " + std::to_string(approx) + " records, over the limit of " +
                               std::to_string(static_cast<std::size_t>(kMaxRecords)));
        const double want = std::max<double>(needed, approx) * 1.25 + 64.0;
        recordCapacity = static_cast<std::size_t>(std::min(want, kMaxRecords));
    }

    /// The count and indirect arguments of the record-sized passes over `records` records, written by the CPU where
    /// it knows the count (an iteration after no build); as build.comp's writeDispatch writes them.
    void writeDispatch(std::size_t records) const {
        GLuint block[CULLIDE_COUNTERS_SIZE - CULLIDE_DISPATCH_RECORDS] = {};
        const auto at = [&](int slot) -> GLuint& { return block[slot - CULLIDE_DISPATCH_RECORDS]; };
        // A grid of at least `count` invocations: work groups along x, as many rows of them along z as needed.
        const auto grid = [&](int slot, std::size_t count, GLuint layers) {
            const std::size_t groups = (count + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
            const std::size_t x = std::min(groups, maxGroups);
            at(slot) = static_cast<GLuint>(x);
            at(slot + 1) = layers;
            at(slot + 2) = static_cast<GLuint>(x == 0 ? 0 : (groups + x - 1) / x);
        };
        grid(CULLIDE_DISPATCH_CULL, records, 3);
        grid(CULLIDE_DISPATCH_SURVIVE, std::max(records, levelItems->size()), 1);
        at(CULLIDE_DISPATCH_RECORDS) = static_cast<GLuint>(records);
        at(CULLIDE_DISPATCH_NEEDED) = static_cast<GLuint>(records);
        const float approx = static_cast<float>(records);
        std::memcpy(&at(CULLIDE_DISPATCH_NEEDED_APPROX), &approx, sizeof approx);
        at(CULLIDE_DISPATCH_DRAW) = static_cast<GLuint>(9 * records);
        at(CULLIDE_DISPATCH_DRAW + 1) = 1;
        glNamedBufferSubData(buffers[kCounters], 4 * CULLIDE_DISPATCH_RECORDS, sizeof block, block);
    }

    void startTiming() {
        if (timing) return;
        timing = true;
        timedSpan = Clock::now();
        if (timer) glBeginQuery(GL_TIME_ELAPSED, timer);
    }

    /// Binds what every pass reads and writes and clears the images, the flags and the counters.
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
        glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_ALIVE_BITS,
                                  static_cast<GLsizeiptr>(4 * (counterWords(itemCount) - CULLIDE_ALIVE_BITS)),
                                  GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
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

    /// One iteration on the device: the records first where they were just counted, the three passes over the
    /// alive items' records, and the survivor pass, which also packs the records of the items still alive; the
    /// record-sized passes dispatched indirectly. Reads back the counters, the dispatch block and the alive set as
    /// bits (128 bytes + a bit per item) in one read-back. Where the build before it found the record
    /// buffers short, the iteration pruned nothing: the buffers grow and the build and the iteration run again.
    IterationResult runIteration(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) {
        const std::size_t words = counterWords(levelItems->size());
        for (int attempt = 0;; ++attempt) {
            const bool afterBuild = dispatchFromBuild;
            issueIteration(view, idBits, level, stats);
            readScratch.resize(words);
            readBack(buffers[kCounters], 0, 4 * words, readScratch.data(), level, stats);
            const std::uint32_t* counters = readScratch.data();
            recordGpuTime(timer ? timerResultMs(timer, msSince(timedSpan)) : -1.0, level, stats);
            checkGlError("a visibility iteration");
            const std::size_t ranOver = counters[CULLIDE_DISPATCH_RECORDS];
            level.primitivesDrawn += 3 * 3 * ranOver;  // three passes over three views
            if (counters[CULLIDE_DISPATCH_SHORT] != 0) {
                if (attempt == 2) throw BackendError("the record buffers were short after growing twice");
                level.shortBuilds += 1;
                float approx = 0.0f;
                std::memcpy(&approx, &counters[CULLIDE_DISPATCH_NEEDED_APPROX], sizeof approx);
                growRecords(counters[CULLIDE_DISPATCH_NEEDED], approx);
                const auto setUp = Clock::now();
                buildRecords(view, false, level, stats);  // the items' boxes are built already
                level.setupMs += msSince(setUp);
                continue;
            }
            if (afterBuild) level.records += counters[CULLIDE_DISPATCH_NEEDED];
            aliveBits.assign(counters + CULLIDE_ALIVE_BITS, counters + words);
            recordCount = counters[CULLIDE_COUNTER_RECORDS];
            std::swap(buffers[kPrims], buffers[kPrimsNext]);
            std::swap(capacity[kPrims], capacity[kPrimsNext]);
            IterationResult r;
            r.overflows = counters[CULLIDE_COUNTER_OVERFLOWS];
            r.alive = counters[CULLIDE_COUNTER_ALIVE];
            r.ownerMin = counters[CULLIDE_COUNTER_OWNER_MIN];
            r.ownerMax = counters[CULLIDE_COUNTER_OWNER_MAX];
            for (int a = 0; a < 3; ++a) {
                r.bounds.min[a] = fromOrderedBits(counters[CULLIDE_COUNTER_LO + a]);
                r.bounds.max[a] = fromOrderedBits(counters[CULLIDE_COUNTER_HI + a]);
            }
            return r;
        }
    }

    /// Issues one iteration's passes (nothing waits for them) and ends the timed span.
    void issueIteration(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) {
        const std::size_t itemCount = levelItems->size();
        startTiming();
        prepareIteration(itemCount);
        if (!dispatchFromBuild) {
            writeDispatch(recordCount);
            stats.bytesUploaded += 4 * (CULLIDE_COUNTERS_SIZE - CULLIDE_DISPATCH_RECORDS);
        }
        dispatchFromBuild = false;
        if (settings.backend == Backend::Raster) {
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_RECORDS, buffers[kRecords]);
            glUseProgram(setupProgram);
            setUniforms(idBits, view);
            glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_CULL);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            level.draws += 1;
            stats.draws += 1;
        }
        glUseProgram(program);
        setUniforms(idBits, view);
        draw(CULLIDE_PASS_NEAREST, level, stats);
        draw(CULLIDE_PASS_SECOND, level, stats);
        draw(CULLIDE_PASS_FLAG, level, stats);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_PRIMS_OUT, buffers[kPrimsNext]);
        glUseProgram(surviveProgram);
        glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(itemCount));
        glUniform1ui(CULLIDE_LOC_REQUIRED, requiredFlags(settings.axes));
        glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_SURVIVE);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        level.draws += 1;
        stats.draws += 1;
        if (timer) glEndQuery(GL_TIME_ELAPSED);
        timing = false;
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
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

    /// The alive set as 0/1 per item, from the last iteration's read-back (nothing is waited for).
    void readAlive(std::size_t itemCount, std::vector<std::uint8_t>& alive) const {
        alive.resize(itemCount);
        for (std::size_t i = 0; i < itemCount; ++i) alive[i] = (aliveBits[i / 32] >> (i % 32)) & 1u;
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
}

namespace {

/// The records are rebuilt (bands fitted to the new view) when the view has shrunk to a quarter along some axis:
/// each pixel band of a record grows with the square of the view's shrinking.
bool recordsStale(const Aabb& view, const Aabb& recordedView) {
    const Vec3 now = view.extent(), then = recordedView.extent();
    for (int a = 0; a < 3; ++a)
        if (4.0 * now[a] < then[a]) return true;
    return false;
}

}  // namespace

void VisibilityPass::beginLevel(const LevelItems& items, const View& view, LevelStats& level, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    if (s.timing) {  // a level abandoned between its build and its first iteration
        if (s.timer) glEndQuery(GL_TIME_ELAPSED);
        s.timing = false;
    }
    const auto setUp = Clock::now();
    s.levelItems = &items;
    s.uploadItems(items, level, stats);
    s.buildRecords(view, true, level, stats);
    s.recordedView = view.box;
    level.setupMs += msSince(setUp);
}

IterationResult VisibilityPass::iterate(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    if (recordsStale(view.box, s.recordedView)) {
        const auto setUp = Clock::now();
        s.buildRecords(view, false, level, stats);
        s.recordedView = view.box;
        level.setupMs += msSince(setUp);
    }
    return s.runIteration(view, idBits, level, stats);
}

void VisibilityPass::readAlive(std::vector<std::uint8_t>& alive, LevelStats& /*level*/, Stats& /*stats*/) {
    m_impl->readAlive(m_impl->levelItems->size(), alive);
}

}  // namespace cullide::gl

namespace cullide {

std::unique_ptr<PruningBackend> createGlPruningBackend(const Settings& settings, const GlBackendOptions& options) {
    return std::make_unique<gl::VisibilityPass>(settings, options);
}

}  // namespace cullide
