#include "gl/VisibilityPass.h"

#include "bindings.h"
#include "gl/EglContext.h"
#include "gl/GlApi.h"
#include "gl/GlProgram.h"
#include "CullerBackends.h"
#include "VisibilityLevel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
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

/// Grows a buffer to hold at least `bytes`.
void reserveBuffer(GLuint buffer, std::size_t& capacity, std::size_t bytes) {
    if (bytes > capacity || capacity == 0) {
        capacity = std::max<std::size_t>({bytes, capacity + capacity / 2, 256});
        glNamedBufferData(buffer, static_cast<GLsizeiptr>(capacity), nullptr, GL_DYNAMIC_DRAW);
    }
}

/// Grows a buffer to at least `bytes` and uploads `data`.
void uploadBuffer(GLuint buffer, std::size_t& capacity, const void* data, std::size_t bytes) {
    reserveBuffer(buffer, capacity, bytes);
    if (bytes > 0) glNamedBufferSubData(buffer, 0, static_cast<GLsizeiptr>(bytes), data);
}

/// Uploads `data` except its first `keepBytes`, which the buffer already holds (`valid` bytes of it are from the
/// previous upload); a buffer that has to grow loses its contents and is filled whole. Returns the bytes sent.
std::size_t uploadAfterPrefix(GLuint buffer, std::size_t& capacity, std::size_t& valid, const void* data,
                              std::size_t bytes, std::size_t keepBytes) {
    if (bytes > capacity || capacity == 0) {
        reserveBuffer(buffer, capacity, bytes);
        keepBytes = 0;
    }
    keepBytes = std::min({keepBytes, valid, bytes});
    if (bytes > keepBytes)
        glNamedBufferSubData(buffer, static_cast<GLintptr>(keepBytes), static_cast<GLsizeiptr>(bytes - keepBytes),
                             static_cast<const unsigned char*>(data) + keepBytes);
    valid = bytes;
    return bytes - keepBytes;
}


/// A timer-query result is plausible when at most this factor times the CPU wall time of the same span plus this
/// slack (clock-rate differences, timer granularity).
constexpr double kTimerFactor = 1.02;
constexpr double kTimerSlackMs = 0.25;

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
    kPrimsNext,  ///< compact.comp's output; swapped with kPrims after every iteration
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
    GLuint compactProgram = 0;
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
    std::vector<std::uint32_t> aliveScratch;
    const GpuGeometry* geometry = nullptr;
    // The level being pruned (beginLevel .. its last iterate).
    const LevelItems* levelItems = nullptr;
    std::size_t recordCount = 0;  ///< records of the alive items, in kPrims
    bool recordsPending = false;  ///< counted (countRecords), not yet written: the next iteration writes them first
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
        compactProgram = linkProgram({compileShader(GL_COMPUTE_SHADER, {"compact.comp"})}, "the compaction program");
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
        reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * CULLIDE_COUNTER_COUNT);
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
        glDeleteProgram(compactProgram);
        glDeleteProgram(buildProgram);
    }

    /// `count` invocations (times `layers` in y) in dispatches of at most GL_MAX_COMPUTE_WORK_GROUP_COUNT[0]
    /// groups each; the program reads its first index from CULLIDE_LOC_PRIM_BASE.
    void dispatchAll(std::size_t count, GLuint layers) const {
        const std::size_t groups = (count + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
        for (std::size_t first = 0; first < groups; first += maxGroups) {
            glUniform1ui(CULLIDE_LOC_PRIM_BASE, static_cast<GLuint>(first * CULLIDE_COMPUTE_GROUP_SIZE));
            glDispatchCompute(static_cast<GLuint>(std::min<std::size_t>(maxGroups, groups - first)), layers, 1);
        }
        glUniform1ui(CULLIDE_LOC_PRIM_BASE, 0);
    }

    void draw(int pass, std::size_t primCount, LevelStats& level, Stats& stats) {
        glUniform1i(CULLIDE_LOC_PASS, pass);
        if (settings.backend == Backend::Compute) {
            dispatchAll(primCount, 3);
        } else {
            const ThirdPartyLeakScope ignoreMesaDrawLeak;
            glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(3 * 3 * primCount));  // 3 views x primCount records
        }
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
        level.draws += 1;
        level.primitivesDrawn += 3 * primCount;
        stats.draws += 1;
    }

    void setUniforms(std::size_t primCount, std::uint32_t idBits, const View& view) const {
        glUniform1i(CULLIDE_LOC_RESOLUTION, settings.resolution);
        glUniform3fv(CULLIDE_LOC_VIEW_LO, 1, view.lo);
        glUniform3fv(CULLIDE_LOC_PIXEL_SCALE, 1, view.pixelScale);
        glUniform3fv(CULLIDE_LOC_DEPTH_SCALE, 1, view.depthScale);
        glUniform3fv(CULLIDE_LOC_HALF_SIZE, 1, view.halfSize);
        glUniform3fv(CULLIDE_LOC_DEPTH_PAD, 1, view.depthPad);
        glUniform1ui(CULLIDE_LOC_ID_BITS, idBits);
        glUniform1i(CULLIDE_LOC_CONSERVATIVE, settings.mode == Mode::Reliable ? 1 : 0);
        glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(primCount));
        glUniform1ui(CULLIDE_LOC_AXES, settings.axes);
    }

    /// Sends what the record build and the survivor pass need of the level's items (their primitives and owners)
    /// and clears their boxes (built by countRecords) and the alive set (every item alive).
    void uploadItems(const LevelItems& items, LevelStats& level, Stats& stats) {
        const std::size_t n = items.size();
        const auto send = Clock::now();
        uploadBuffer(buffers[kOwners], capacity[kOwners], items.owner.data(), n * 4);
        uploadBuffer(buffers[kPrimBegin], capacity[kPrimBegin], items.primBegin.data(), items.primBegin.size() * 4);
        uploadBuffer(buffers[kItemPrims], capacity[kItemPrims], items.prims.data(), items.prims.size() * 4);
        stats.bytesUploaded += (n + items.primBegin.size() + items.prims.size()) * 4;
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
        dispatchAll(invocations, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        level.draws += 1;
        stats.draws += 1;
    }

    /// Counts the records of the level's alive items for `view` on the device (build.comp up to its OFFSETS pass; first
    /// its BOUNDS pass where `withBounds`: at a level's start) and reads back their number, to size the record
    /// buffers and the passes; writeRecords writes them. On the compute back-end each primitive is split into
    /// bands of its largest footprint over the three views. The passes' GPU time counts as the level's, the
    /// read-back as its waiting.
    void countRecords(const View& view, bool withBounds, LevelStats& level, Stats& stats) {
        const std::size_t primCount = levelItems->prims.size();
        const std::size_t groups = (primCount + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
        if (groups > kMaxBuildGroups)
            throw BackendError("a level of " + std::to_string(primCount) + " primitives is over the limit of " +
                               std::to_string(kMaxBuildGroups * CULLIDE_COMPUTE_GROUP_SIZE));
        reserveBuffer(buffers[kBands], capacity[kBands], primCount * 4);
        reserveBuffer(buffers[kBuild], capacity[kBuild], (CULLIDE_BUILD_GROUPS + groups) * 4);
        bindBuffers();
        glUseProgram(buildProgram);
        glUniform3fv(CULLIDE_LOC_PIXEL_SCALE, 1, view.pixelScale);
        glUniform3fv(CULLIDE_LOC_HALF_SIZE, 1, view.halfSize);
        setBuildUniforms();
        glUniform1ui(CULLIDE_LOC_GROUPS, static_cast<GLuint>(groups));
        const auto timedSpan = Clock::now();
        if (timer) glBeginQuery(GL_TIME_ELAPSED, timer);
        if (withBounds) buildPass(CULLIDE_BUILD_PASS_BOUNDS, primCount, level, stats);
        if (bands != CULLIDE_BANDS_NONE) {
            buildPass(CULLIDE_BUILD_PASS_FOOTPRINTS, primCount, level, stats);
            buildPass(CULLIDE_BUILD_PASS_SCALE, 1, level, stats);
        }
        buildPass(CULLIDE_BUILD_PASS_COUNT, primCount, level, stats);
        buildPass(CULLIDE_BUILD_PASS_OFFSETS, 1, level, stats);
        if (timer) glEndQuery(GL_TIME_ELAPSED);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        GLuint total[2] = {};
        readBack(buffers[kBuild], 4 * CULLIDE_BUILD_TOTAL, sizeof total, total, level, stats);
        recordGpuTime(timer ? timerResultMs(timer, msSince(timedSpan)) : -1.0, level, stats);
        checkGlError("counting a level's records");
        float approx = 0.0f;
        std::memcpy(&approx, &total[1], sizeof approx);
        if (!(approx <= kMaxRecords))  // also NaN
            throw BackendError("a level needs about " + std::to_string(approx) + " records, over the limit of " +
                               std::to_string(static_cast<std::size_t>(kMaxRecords)));
        recordCount = total[0];
        recordsPending = true;
        level.records += recordCount;
        level.recordBuilds += 1;
    }

    /// build.comp's WRITE pass: the counted records into kPrims (bound by prepareIteration).
    void writeRecords(LevelStats& level, Stats& stats) {
        glUseProgram(buildProgram);
        setBuildUniforms();
        buildPass(CULLIDE_BUILD_PASS_WRITE, levelItems->prims.size(), level, stats);
        recordsPending = false;
    }

    /// The level's sizes and the band policy, for every pass of build.comp.
    void setBuildUniforms() const {
        glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(levelItems->size()));
        glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(levelItems->prims.size()));
        glUniform1i(CULLIDE_LOC_BANDS, bands);
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
        for (GLuint unit = 0; unit < 4; ++unit)
            glBindImageTexture(unit, images[unit], 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
        reserveBuffer(buffers[kPrims], capacity[kPrims], recordCount * 16);
        bindBuffers();
        glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
        glViewport(0, 0, 3 * settings.resolution, settings.resolution);
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glBindVertexArray(vao);
    }

    /// One iteration on the device: the records first where they were just counted, the three passes over the
    /// alive items' records, the survivor pass, and the compaction of the records to those of the items still
    /// alive. Reads back only the counters (44 bytes).
    IterationResult runIteration(const View& view, std::uint32_t idBits, std::size_t itemCount, LevelStats& level,
                                 Stats& stats) {
        prepareIteration(itemCount);
        const auto timedSpan = Clock::now();
        if (timer) glBeginQuery(GL_TIME_ELAPSED, timer);
        if (recordsPending) writeRecords(level, stats);
        if (settings.backend == Backend::Raster) {
            reserveBuffer(buffers[kRecords], capacity[kRecords], 3 * recordCount * kRecordBytes);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_RECORDS, buffers[kRecords]);
            glUseProgram(setupProgram);
            setUniforms(recordCount, idBits, view);
            dispatchAll(recordCount, 3);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            level.draws += 1;
            stats.draws += 1;
        }
        glUseProgram(program);
        setUniforms(recordCount, idBits, view);
        draw(CULLIDE_PASS_NEAREST, recordCount, level, stats);
        draw(CULLIDE_PASS_SECOND, recordCount, level, stats);
        draw(CULLIDE_PASS_FLAG, recordCount, level, stats);
        glUseProgram(surviveProgram);
        glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(itemCount));
        glUniform1ui(CULLIDE_LOC_REQUIRED, requiredFlags(settings.axes));
        dispatchAll(itemCount, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        reserveBuffer(buffers[kPrimsNext], capacity[kPrimsNext], recordCount * 16);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_PRIMS_OUT, buffers[kPrimsNext]);
        glUseProgram(compactProgram);
        glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(recordCount));
        dispatchAll(recordCount, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        level.draws += 2;
        stats.draws += 2;
        if (timer) glEndQuery(GL_TIME_ELAPSED);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        GLuint counters[CULLIDE_COUNTER_COUNT] = {};
        readBack(buffers[kCounters], 0, sizeof counters, counters, level, stats);
        recordGpuTime(timer ? timerResultMs(timer, msSince(timedSpan)) : -1.0, level, stats);
        checkGlError("a visibility iteration");
        IterationResult r;
        r.overflows = counters[CULLIDE_COUNTER_OVERFLOWS];
        r.alive = counters[CULLIDE_COUNTER_ALIVE];
        r.ownerMin = counters[CULLIDE_COUNTER_OWNER_MIN];
        r.ownerMax = counters[CULLIDE_COUNTER_OWNER_MAX];
        recordCount = counters[CULLIDE_COUNTER_RECORDS];
        std::swap(buffers[kPrims], buffers[kPrimsNext]);
        std::swap(capacity[kPrims], capacity[kPrimsNext]);
        for (int a = 0; a < 3; ++a) {
            r.bounds.min[a] = fromOrderedBits(counters[CULLIDE_COUNTER_LO + a]);
            r.bounds.max[a] = fromOrderedBits(counters[CULLIDE_COUNTER_HI + a]);
        }
        return r;
    }

    /// Reads `bytes` at `offset` of `buffer` back into `to`: blocks until the device has finished the work submitted
    /// before, which the level's waitMs counts (with the tests' readBackDelayMs inside it).
    void readBack(GLuint buffer, std::size_t offset, std::size_t bytes, void* to, LevelStats& level, Stats& stats) {
        const auto waitStart = Clock::now();
        glGetNamedBufferSubData(buffer, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(bytes), to);
        if (readBackDelayMs > 0.0)
            std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(readBackDelayMs));
        level.waitMs += msSince(waitStart);
        stats.bytesReadBack += bytes;
    }

    /// The device's alive set, as 0/1 per item.
    void readAlive(std::size_t itemCount, std::vector<std::uint8_t>& alive, LevelStats& level, Stats& stats) {
        aliveScratch.resize(itemCount);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        readBack(buffers[kAlive], 0, itemCount * 4, aliveScratch.data(), level, stats);
        alive.resize(itemCount);
        for (std::size_t i = 0; i < itemCount; ++i) alive[i] = aliveScratch[i] != 0 ? 1 : 0;
    }

    /// The GPU time of the span just timed by `query`, in ms, or -1 when it is not available or not plausible:
    /// the GPU cannot have spent longer between glBeginQuery and glEndQuery than the CPU waited from issuing the
    /// first to holding the result (`wallMs`). llvmpipe (Mesa 22.3) fails this once per context: its first
    /// TIME_ELAPSED result, with either back-end, is the end time stamp less a start that was never stamped (0),
    /// i.e. CLOCK_MONOTONIC — the machine's uptime; its later results are plausible.
    static double timerResultMs(GLuint query, double wallMs) {
        // The counters were just read back, so waiting for the result costs next to nothing; a driver that still
        // says it is not available has no trustworthy result.
        GLuint64 ns = 0;
        glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
        GLint available = GL_FALSE;
        glGetQueryObjectiv(query, GL_QUERY_RESULT_AVAILABLE, &available);
        const double ms = static_cast<double>(ns) * 1e-6;
        if (available != GL_TRUE || !std::isfinite(ms) || ms > kTimerFactor * wallMs + kTimerSlackMs) return -1.0;
        return ms;
    }

    /// Adds one iteration's GPU time (`ms` < 0: absent) to the level and the frame. One absent iteration makes
    /// the level's and the frame's timings absent: a partial sum would read as a time.
    static void recordGpuTime(double ms, LevelStats& level, Stats& stats) {
        if (ms < 0.0) {
            level.gpuTimingValid = false;
            level.gpuMs = 0.0;
            stats.gpuTimingValid = false;
            stats.gpuMs = 0.0;
            return;
        }
        if (level.gpuTimingValid) level.gpuMs += ms;
        if (stats.gpuTimingValid) stats.gpuMs += ms;
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
    for (std::size_t& v : m_impl->valid) v = 0;
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

/// Runs a level's set-up and adds its time to setupMs, less what it spent blocked in read-backs (the record count's),
/// which waitMs counts: set-up and waits are disjoint parts of cpuMs (on a hardware device the read-back is most of
/// the set-up).
template <class SetUp>
void timeSetUp(LevelStats& level, SetUp&& setUp) {
    const auto t0 = Clock::now();
    const double waitedBefore = level.waitMs;
    setUp();
    level.setupMs += msSince(t0) - (level.waitMs - waitedBefore);
}

}  // namespace

void VisibilityPass::beginLevel(const LevelItems& items, const View& view, LevelStats& level, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    timeSetUp(level, [&] {
        s.levelItems = &items;
        s.uploadItems(items, level, stats);
        s.countRecords(view, true, level, stats);
        s.recordedView = view.box;
    });
}

IterationResult VisibilityPass::iterate(const View& view, std::uint32_t idBits, LevelStats& level, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    if (recordsStale(view.box, s.recordedView)) {
        timeSetUp(level, [&] {
            s.countRecords(view, false, level, stats);
            s.recordedView = view.box;
        });
    }
    return s.runIteration(view, idBits, s.levelItems->size(), level, stats);
}

void VisibilityPass::readAlive(std::vector<std::uint8_t>& alive, LevelStats& level, Stats& stats) {
    Impl& s = *m_impl;
    s.context.makeCurrent();
    s.readAlive(s.levelItems->size(), alive, level, stats);
}

}  // namespace cullide::gl

namespace cullide {

std::unique_ptr<PruningBackend> createGlPruningBackend(const Settings& settings, const GlBackendOptions& options) {
    return std::make_unique<gl::VisibilityPass>(settings, options);
}

}  // namespace cullide
