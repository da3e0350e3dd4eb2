#include "gl/LevelDevice.h"

#include "gl/GlBuffers.h"
#include "gl/GlProgram.h"
#include "gl/GpuTimes.h"
#include "gl/ViewRecords.h"
#include "DeviceExact.h"
#include "VisibilityLevel.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <thread>

namespace cullide::gl {
namespace {

/// Records of one build beyond which the level gives up (BackendError: that frame prunes nothing): 64 Mi records,
/// 1 GiB of device memory. A build makes about (primitives + max(CULLIDE_TARGET_INVOCATIONS, footprint pixels /
/// CULLIDE_PIXELS_PER_INVOCATION)) records on a hardware GPU, primitives + footprint pixels / 4,096 on llvmpipe.
constexpr double kMaxRecords = 67108864.0;

/// Work groups of primitives (64 each) beyond which a level gives up (BackendError, as above): 16.7 M primitives.
/// build.comp's single-group passes loop over the work groups, about 13 iterations per 64 of them, and llvmpipe
/// silently ends a shader's loops after 65,535 iterations.
constexpr std::size_t kMaxBuildGroups = 262144;

constexpr std::size_t kRecordBytes = 7 * 16;  // PrimRecord in common.glsl

/// map.comp's MappedRecord (std430).
struct MappedRecord {
    double m[12];  ///< the linear part row by row, then the translation
    std::uint32_t localBase;
    std::uint32_t baseVertex;
    std::uint32_t count;
    std::uint32_t firstMapped;  ///< the vertices of the records before it, summed
};
static_assert(sizeof(MappedRecord) == 112, "map.comp's std430 layout");

MappedRecord toMappedRecord(const MappedMesh& mesh) {
    MappedRecord r{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) r.m[3 * i + j] = mesh.transform.linear(i, j);
        r.m[9 + i] = mesh.transform.translation[i];
    }
    r.localBase = mesh.localBase;
    r.baseVertex = mesh.baseVertex;
    r.count = mesh.count;
    return r;
}

/// Waits for the work submitted so far (a fence) and, in tests, for a slow device's round trip (`delayEnd`), until
/// `until` at the latest: false where that came first.
bool waitForDeviceUntil(Clock::time_point until, Clock::time_point delayEnd) {
    const GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    GLbitfield flags = GL_SYNC_FLUSH_COMMANDS_BIT;
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(until - Clock::now()).count();
        const GLenum r = glClientWaitSync(fence, flags, static_cast<GLuint64>(std::max<long long>(0, left)));
        flags = 0;
        if (r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED) break;
        if (r != GL_TIMEOUT_EXPIRED) {
            glDeleteSync(fence);
            throw BackendError("waiting for the device failed");
        }
        if (Clock::now() > until) {
            glDeleteSync(fence);
            return false;
        }
    }
    glDeleteSync(fence);
    if (delayEnd <= until || delayEnd <= Clock::now()) return true;  // no delay, or it has passed
    std::this_thread::sleep_until(until);
    return false;
}

}  // namespace

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

std::size_t counterWords(std::size_t items) { return CULLIDE_ALIVE_BITS + (items + 31) / 32; }

LevelDevice::LevelDevice(std::unique_ptr<EglContext> c, const Settings& s, const GlBackendOptions& options)
    : ownContext(std::move(c)), context(*ownContext), settings(s), readBackDelayMs(options.readBackDelayMs),
      positionsAfterUpload(options.positionsAfterUpload), boxesAfterUpload(options.boxesAfterUpload) {
    if (options.exactCapacity > 0) exactCapacity = options.exactCapacity;
    context.makeCurrent();
    if (settings.backend == Backend::Compute) {
        program = linkProgram(Program::Cull);
        secondProgram = linkProgram(Program::Second);
        flagProgram = linkProgram(Program::Flag);
    } else {
        setupProgram = linkProgram(Program::CullSetup);
        program = linkProgram(Program::CullRaster);
        surviveProgram = linkProgram(Program::Survive);
    }
    buildProgram = linkProgram(Program::Build);
    mapProgram = linkProgram(Program::Map);
    boxesProgram = linkProgram(Program::GroupBoxes);
    startProgram = linkProgram(Program::Start);
    exactProgram = linkProgram(Program::Exact);
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
    hasTimers = context.hasTimerQueries();
    GLint limit = 65535;
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &limit);
    maxGroups = static_cast<std::size_t>(std::max(1, limit));
    if (options.maxWorkGroups > 0) maxGroups = std::min(maxGroups, options.maxWorkGroups);
    reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * CULLIDE_ALIVE_BITS);
    reserveBuffer(buffers[kViews], capacity[kViews], sizeof(ViewRecord) * (CULLIDE_MAX_ITERATIONS + 1));
    for (Buffer b : {kRanges, kParentAlive, kPrimBegin, kStash, kStashViews, kOrdered, kBands, kBoxRanges})
        reserveBuffer(buffers[b], capacity[b], 4);
    checkGlError("creating the visibility pass");
    // Every call makes the context current on its own thread: the culler may be used from another thread than
    // the one that made it (the Bullet adapter makes Culling::Auto's culler off the step's thread).
    context.release();
}

LevelDevice::~LevelDevice() {
    if (!context.tryMakeCurrent()) return;  // the context is gone: so are its objects
    if (!timers.empty()) glDeleteQueries(static_cast<GLsizei>(timers.size()), timers.data());
    glDeleteFramebuffers(1, &framebuffer);
    glDeleteTextures(4, images);
    glDeleteBuffers(kBufferCount, buffers);
    glDeleteVertexArrays(1, &vao);
    glDeleteProgram(program);
    if (setupProgram) glDeleteProgram(setupProgram);
    if (surviveProgram) glDeleteProgram(surviveProgram);
    if (secondProgram) glDeleteProgram(secondProgram);
    if (flagProgram) glDeleteProgram(flagProgram);
    glDeleteProgram(buildProgram);
    glDeleteProgram(mapProgram);
    glDeleteProgram(boxesProgram);
    glDeleteProgram(startProgram);
    glDeleteProgram(exactProgram);
}

std::size_t LevelDevice::dispatchAll(std::size_t count, GLint baseLocation) const {
    const std::size_t groups = (count + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
    std::size_t dispatches = 0;
    for (std::size_t first = 0; first < groups; first += maxGroups, ++dispatches) {
        glUniform1ui(baseLocation, static_cast<GLuint>(first * CULLIDE_COMPUTE_GROUP_SIZE));
        glDispatchCompute(static_cast<GLuint>(std::min<std::size_t>(maxGroups, groups - first)), 1, 1);
    }
    glUniform1ui(baseLocation, 0);
    return dispatches;
}

void LevelDevice::uploadPositions(const GpuGeometry& g, Stats& stats) {
    const std::size_t allBytes = g.vertexCount() * 12;  // the mapped meshes' too
    growKeeping(buffers[kPositions], capacity[kPositions], valid[kPositions], allBytes);
    stats.bytesUploaded += uploadAfterPrefix(buffers[kPositions], capacity[kPositions], valid[kPositions],
                                             g.positions.data(), g.positions.size() * 4, g.keptPositions * 4);
    // The local vertices even without mapped meshes (nothing is sent then unless they changed): what the device
    // holds of them must always be the last upload's, or a store that started over could keep stale slots there.
    stats.bytesUploaded += uploadAfterPrefix(buffers[kLocal], capacity[kLocal], valid[kLocal], g.local.data(),
                                             g.local.size() * 8, g.keptLocal * 8);
    if (g.mapped.empty()) return readForTests(kPositions, 3 * g.vertexCount(), positionsAfterUpload.get());
    std::vector<MappedRecord> records(g.mapped.size());
    std::size_t vertices = 0;  // mapped, summed
    for (std::size_t i = 0; i < records.size(); ++i) {
        records[i] = toMappedRecord(g.mapped[i]);
        records[i].firstMapped = static_cast<std::uint32_t>(vertices);
        vertices += g.mapped[i].count;
    }
    if (vertices > 0xFFFFFFFFu) throw BackendError("over 2^32 vertices of transformed meshes in one upload");
    uploadBuffer(buffers[kMapped], capacity[kMapped], records.data(), records.size() * sizeof(MappedRecord));
    stats.bytesUploaded += records.size() * sizeof(MappedRecord);
    glUseProgram(mapProgram);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_POSITIONS, buffers[kPositions]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_LOCAL, buffers[kLocal]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_MAPPED, buffers[kMapped]);
    glUniform3d(CULLIDE_LOC_ORIGIN, g.origin.x(), g.origin.y(), g.origin.z());
    glUniform1ui(CULLIDE_LOC_MAPPED_MESHES, static_cast<GLuint>(records.size()));
    glUniform1ui(CULLIDE_LOC_MAPPED_VERTICES, static_cast<GLuint>(vertices));
    stats.draws += dispatchAll(vertices, CULLIDE_LOC_MAPPED_BASE);
    // Read by the passes after it, and overwritten by the next upload's glNamedBufferSubData only after it.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    readForTests(kPositions, 3 * g.vertexCount(), positionsAfterUpload.get());
}

void LevelDevice::uploadBoxes(const GpuGeometry& g, Stats& stats) {
    const std::size_t built = g.builtRanges.size() / 2;
    growKeeping(buffers[kBoxes], capacity[kBoxes], heldBoxes.size(), g.boxes.size() * 4 + built * 24);
    // A cluster at rest keeps its boxes; an object moving sends its own (its object box; a static mesh's groups').
    stats.bytesUploaded +=
        uploadChanged(buffers[kBoxes], capacity[kBoxes], heldBoxes, g.boxes.data(), g.boxes.size() * 4);
    if (built > 0) {
        stats.bytesUploaded += uploadChanged(buffers[kBoxRanges], capacity[kBoxRanges], heldRanges,
                                             g.builtRanges.data(), g.builtRanges.size() * 4);
        glUseProgram(boxesProgram);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_POSITIONS, buffers[kPositions]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_INDICES, buffers[kIndices]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_ORDERED, buffers[kOrdered]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_BOX_RANGES, buffers[kBoxRanges]);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_BOXES, buffers[kBoxes]);
        glUniform1ui(CULLIDE_LOC_BOX_FIRST, static_cast<GLuint>(g.boxes.size() / 6));
        glUniform1ui(CULLIDE_LOC_BOX_COUNT, static_cast<GLuint>(built));
        glUniform1f(CULLIDE_LOC_BOX_INFLATE, g.builtInflate);
        stats.draws += dispatchAll(built, CULLIDE_LOC_BOX_BASE);
        // Read by the passes after it, and overwritten by the next upload's glNamedBufferSubData only after it.
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
    readForTests(kBoxes, g.boxes.size() + 6 * built, boxesAfterUpload.get());
}

void LevelDevice::readForTests(Buffer buffer, std::size_t floats, std::vector<float>* to) const {
    if (to == nullptr) return;
    to->assign(floats, 0.0f);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);  // what a shader wrote (map.comp's positions)
    glGetNamedBufferSubData(buffers[buffer], 0, static_cast<GLsizeiptr>(floats * 4), to->data());
}

void LevelDevice::draw(int pass, LevelStats& level, Stats& stats) const {
    glUniform1i(CULLIDE_LOC_PASS, pass);
    if (settings.backend == Backend::Compute) {
        glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_CULL);
    } else {
        const ThirdPartyLeakScope ignoreMesaDrawLeak;
        // 3 views x the records, a triangle each
        const std::uintptr_t offset = 4 * CULLIDE_DISPATCH_DRAW;
        glDrawArraysIndirect(GL_TRIANGLES, reinterpret_cast<const void*>(offset));
    }
    // The compute back-end's flag pass ends the iteration: it writes the next one's indirect arguments and what the
    // level's copies and read-back take.
    const bool endsIteration = settings.backend == Backend::Compute && pass == CULLIDE_PASS_FLAG;
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT |
                    (endsIteration ? GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT : 0));
    level.draws += 1;
    stats.draws += 1;
}

void LevelDevice::setLevelUniforms(double coordinateBound) const {
    for (GLuint p : {program, setupProgram, secondProgram, flagProgram}) {
        if (p == 0) continue;  // no setup program on the compute back-end
        glProgramUniform1i(p, CULLIDE_LOC_RESOLUTION, settings.resolution);
        glProgramUniform1i(p, CULLIDE_LOC_CONSERVATIVE, settings.mode == Mode::Reliable ? 1 : 0);
        glProgramUniform1ui(p, CULLIDE_LOC_AXES, settings.axes);
    }
    const GLuint s = settings.backend == Backend::Compute ? flagProgram : surviveProgram;  // ends the iterations
    glProgramUniform1ui(s, CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(levelItems->size()));
    glProgramUniform1ui(s, CULLIDE_LOC_REQUIRED, requiredFlags(settings.axes));
    glProgramUniform1ui(s, CULLIDE_LOC_MAX_ITERATIONS, static_cast<GLuint>(settings.maxIterations));
    glProgramUniform1ui(s, CULLIDE_LOC_MAX_GROUPS, static_cast<GLuint>(maxGroups));
    glProgramUniform1i(s, CULLIDE_LOC_RESOLUTION, settings.resolution);
    glProgramUniform1d(s, CULLIDE_LOC_MARGIN, settings.margin);
    glProgramUniform1d(s, CULLIDE_LOC_COORDINATE_BOUND, coordinateBound);
    glProgramUniform1d(s, CULLIDE_LOC_MIN_PRUNE_FRACTION, settings.minPruneFraction);
}

void LevelDevice::uploadItems(const LevelItems& items, const LevelStart& start, LevelStats& level, Stats& stats) {
    const std::size_t n = items.size();
    const bool byObjects = items.describedByObjects();
    const auto send = Clock::now();
    onePrimEach = byObjects || items.onePrimitiveEach();
    // flag.comp decides an item once its last record is done: an item without one would never be.
    const auto& begin = items.primBegin;
    if (settings.backend == Backend::Compute && !onePrimEach &&
        std::adjacent_find(begin.begin(), begin.end(), std::equal_to<std::uint32_t>()) != begin.end())
        throw BackendError("a level item without primitives");
    if (byObjects) {  // start.comp writes the items' owners and primitives and the first view
        sendRanges(items, stats);
        reserveBuffer(buffers[kOwners], capacity[kOwners], n * 4);
        reserveBuffer(buffers[kItemPrims], capacity[kItemPrims], n * 4);
    } else {
        uploadBuffer(buffers[kOwners], capacity[kOwners], items.owner.data(), n * 4);
        uploadBuffer(buffers[kItemPrims], capacity[kItemPrims], items.prims.data(), items.prims.size() * 4);
        const ViewRecord first = toViewRecord(start.view, start.idBits);
        glNamedBufferSubData(buffers[kViews], 0, sizeof first, &first);
        stats.bytesUploaded += n * 4 + items.prims.size() * 4 + sizeof first;
    }
    lastItemCount = n;
    if (!onePrimEach) {
        uploadBuffer(buffers[kPrimBegin], capacity[kPrimBegin], items.primBegin.data(), items.primBegin.size() * 4);
        stats.bytesUploaded += items.primBegin.size() * 4;
    }
    reserveBuffer(buffers[kCounters], capacity[kCounters], 4 * counterWords(n));
    // Every item alive, or none until start.comp marks those that start alive.
    const GLuint zero = 0, startAlive = byObjects ? 0u : static_cast<GLuint>(n);
    const GLuint aliveWord = byObjects ? 0u : 0xFFFFFFFFu, aliveItem = byObjects ? 0u : 1u;
    glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_CHAIN_RAN,
                              4 * (CULLIDE_ALIVE_BITS - CULLIDE_CHAIN_RAN), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_CHAIN_ALIVE_START, 4, GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &startAlive);
    glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_ALIVE_BITS,
                              static_cast<GLsizeiptr>(4 * (counterWords(n) - CULLIDE_ALIVE_BITS)), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &aliveWord);
    reserveBuffer(buffers[kFlags], capacity[kFlags], n * 4);
    reserveBuffer(buffers[kAlive], capacity[kAlive], n * 4);
    reserveBuffer(buffers[kItemBounds], capacity[kItemBounds], n * 32);
    const GLuint empty[2] = {0xFFFFFFFFu, 0u};
    glClearNamedBufferSubData(buffers[kAlive], GL_R32UI, 0, static_cast<GLsizeiptr>(n * 4), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &aliveItem);
    glClearNamedBufferSubData(buffers[kItemBounds], GL_R32UI, 0, static_cast<GLsizeiptr>(n * 12), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &empty[0]);
    glClearNamedBufferSubData(buffers[kItemBounds], GL_R32UI, static_cast<GLintptr>(n * 12),
                              static_cast<GLsizeiptr>(n * 12), GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
    if (byObjects) startItems(items, start.coordinateBound, level, stats);
    level.setupSendMs += msSince(send);
}

void LevelDevice::sendRanges(const LevelItems& items, Stats& stats) {
    // start.comp reads what the ranges name: they must cover the items in order and name what the upload holds.
    const std::vector<ObjectRange>& ranges = items.objectRanges;
    if (geometry == nullptr) throw BackendError("a level described by its objects before any upload");
    if (items.groupSize == 0) throw BackendError("a level described by its objects with groups of no triangle");
    const std::size_t boxCount = geometry->boxes.size() / 6 + geometry->builtRanges.size() / 2;
    const std::size_t triangleCount = geometry->ordered.size();
    std::size_t next = 0;  // the item the next range must begin with
    for (const ObjectRange& r : ranges) {
        const bool isBox = (r.kind & 1u) == CULLIDE_RANGE_BOXES;
        const std::size_t lastParent = isBox ? r.count - 1 : (r.count - 1) / items.groupSize;
        const std::size_t named = isBox ? boxCount : triangleCount;
        const bool fits = r.count > 0 && r.itemBegin == next && r.first + std::size_t{r.count} <= named &&
                          r.partnerBegin <= r.partnerEnd && r.partnerEnd <= items.partnerBoxes.size() &&
                          (!items.inheritsParents || std::size_t{r.parent} + lastParent < lastItemCount);
        if (!fits) throw BackendError("a level's object ranges do not fit its items, the upload or the level before");
        next += r.count;
    }
    const bool partnersFit = std::all_of(items.partnerBoxes.begin(), items.partnerBoxes.end(),
                                         [&](std::uint32_t b) { return b < boxCount; });
    if (next != items.size() || !partnersFit) throw BackendError("a level's object ranges do not cover its items");
    if (items.inheritsParents) {  // the last level's alive set, before this level's replaces it
        reserveBuffer(buffers[kParentAlive], capacity[kParentAlive], std::max<std::size_t>(1, lastItemCount) * 4);
        glCopyNamedBufferSubData(buffers[kAlive], buffers[kParentAlive], 0, 0,
                                 static_cast<GLsizeiptr>(lastItemCount * 4));
    }
    checkExactRequest(items);
    rangeWords.resize(ranges.size() * CULLIDE_RANGE_WORDS);
    std::memcpy(rangeWords.data(), ranges.data(), ranges.size() * sizeof(ObjectRange));
    rangeWords.insert(rangeWords.end(), items.partnerBoxes.begin(), items.partnerBoxes.end());
    exactPartnersWord = rangeWords.size();
    if (items.exact.run) {
        rangeWords.insert(rangeWords.end(), items.exact.partnerBegin.begin(), items.exact.partnerBegin.end());
        rangeWords.insert(rangeWords.end(), items.exact.partners.begin(), items.exact.partners.end());
        rangeWords.insert(rangeWords.end(), items.exact.groupBoxes.begin(), items.exact.groupBoxes.end());
    }
    uploadBuffer(buffers[kRanges], capacity[kRanges], rangeWords.data(), rangeWords.size() * 4);
    stats.bytesUploaded += rangeWords.size() * 4;
}

void LevelDevice::checkExactRequest(const LevelItems& items) const {
    const ExactRequest& x = items.exact;
    if (!x.run) return;
    const std::size_t ranges = items.objectRanges.size();
    const std::size_t boxCount = geometry->boxes.size() / 6 + geometry->builtRanges.size() / 2;
    bool fits = x.partnerBegin.size() == ranges + 1 && x.partnerBegin.front() == 0 && x.groupBoxes.size() == ranges &&
                x.partnerBegin.back() == x.partners.size() && x.chunks > 0 && x.chunks <= 65535;
    for (std::size_t r = 0; fits && r < ranges; ++r) fits = x.partnerBegin[r] <= x.partnerBegin[r + 1];
    std::size_t longest = 0;  // partner items of one range, summed: within the chunks
    for (std::size_t r = 0; fits && r < ranges; ++r) {
        std::size_t sum = 0;
        for (std::uint32_t p = x.partnerBegin[r]; fits && p < x.partnerBegin[r + 1]; ++p) {
            fits = x.partners[p] < ranges;
            if (!fits) break;
            const ObjectRange& other = items.objectRanges[x.partners[p]];
            const std::size_t groups = (other.count + items.groupSize - 1) / items.groupSize;
            fits = (other.kind & 1u) == CULLIDE_RANGE_TRIANGLES && x.groupBoxes[x.partners[p]] + groups <= boxCount;
            sum += other.count;
        }
        longest = std::max(longest, sum);
    }
    fits = fits && x.chunkItems > 0 && x.chunkItems % items.groupSize == 0 &&
           std::size_t{x.chunkItems} * items.groupSize <= kMostExactGroupPairWork;
    if (!fits || longest > std::size_t{x.chunks} * x.chunkItems)
        throw BackendError("a level's exact partners do not fit its ranges");
}

void LevelDevice::findExactPairs(const LevelItems& items, bool firstOfFrame, LevelStats& level, Stats& stats) {
    const ExactRequest& x = items.exact;
    if (firstOfFrame) {
        reserveBuffer(buffers[kExact], capacity[kExact], 4 * (1 + 2 * exactCapacity));
        const GLuint zero = 0;
        glClearNamedBufferSubData(buffers[kExact], GL_R32UI, 0, 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    }
    bindBuffers();
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_EXACT, buffers[kExact]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_EXACT_ITEMS, buffers[kExactItems]);
    glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, buffers[kCounters]);
    glUseProgram(exactProgram);
    glUniform1ui(CULLIDE_LOC_RANGES, static_cast<GLuint>(items.objectRanges.size()));
    glUniform1ui(CULLIDE_LOC_EXACT_PARTNERS, static_cast<GLuint>(exactPartnersWord));
    glUniform1f(CULLIDE_LOC_SLACK, x.slack);
    glUniform1f(CULLIDE_LOC_REACH, x.reach);
    glUniform1i(CULLIDE_LOC_FILTER, x.filter ? 1 : 0);
    glUniform1ui(CULLIDE_LOC_EXACT_CAPACITY, static_cast<GLuint>(exactCapacity));
    glUniform1ui(CULLIDE_LOC_GROUP_SIZE, items.groupSize);
    glUniform1ui(CULLIDE_LOC_CHUNK_ITEMS, x.chunkItems);
    // The level's alive set, and the arguments start.comp wrote for the items that started alive.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
    glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_EXACT);
    level.draws += 1;
    stats.draws += 1;
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

void LevelDevice::clearIterationCounters() const {
    // Cleared, not sent: every counter 0, then the minima (the smallest owner, the boxes' minimum) all ones.
    const GLuint zero = 0, ones = 0xFFFFFFFFu;
    const auto clear = [&](int first, int count, const GLuint& value) {
        glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * first, 4 * count, GL_RED_INTEGER, GL_UNSIGNED_INT,
                                  &value);
    };
    clear(0, CULLIDE_COUNTER_COUNT, zero);
    clear(CULLIDE_COUNTER_OWNER_MIN, 1, ones);
    clear(CULLIDE_COUNTER_LO, 3, ones);
}

void LevelDevice::startItems(const LevelItems& items, double coordinateBound, LevelStats& level, Stats& stats) {
    const std::size_t n = items.size();
    clearIterationCounters();
    bindBuffers();
    glUseProgram(startProgram);
    const std::size_t groups = (n + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
    glUniform1i(CULLIDE_LOC_RESOLUTION, settings.resolution);
    glUniform1d(CULLIDE_LOC_MARGIN, settings.margin);
    glUniform1d(CULLIDE_LOC_COORDINATE_BOUND, coordinateBound);
    glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(n));
    glUniform1ui(CULLIDE_LOC_GROUPS, static_cast<GLuint>(groups));
    glUniform1ui(CULLIDE_LOC_RANGES, static_cast<GLuint>(items.objectRanges.size()));
    glUniform1ui(CULLIDE_LOC_GROUP_SIZE, items.groupSize);
    glUniform1i(CULLIDE_LOC_INHERITS, items.inheritsParents ? 1 : 0);
    glUniform1f(CULLIDE_LOC_SLACK, items.prepassSlack);
    glUniform1ui(CULLIDE_LOC_CHUNKS, items.exact.run ? items.exact.chunks : 0u);
    // Where the exact stage follows: the items that start alive, listed.
    reserveBuffer(buffers[kExactItems], capacity[kExactItems], (items.exact.run ? n : 1) * 4);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_EXACT_ITEMS, buffers[kExactItems]);
    startTiming();
    const std::size_t dispatches = dispatchAll(n, CULLIDE_LOC_ITEM_BASE);
    level.draws += dispatches;
    stats.draws += dispatches;
    // The build reads the items' primitives, owners and alive set and the first view.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

void LevelDevice::bindBuffers() const {
    const std::pair<GLuint, Buffer> bindings[] = {
        {CULLIDE_SSBO_POSITIONS, kPositions},   {CULLIDE_SSBO_INDICES, kIndices},
        {CULLIDE_SSBO_BOXES, kBoxes},           {CULLIDE_SSBO_PRIMS, kPrims},
        {CULLIDE_SSBO_ITEM_OWNER, kOwners},     {CULLIDE_SSBO_FLAGS, kFlags},
        {CULLIDE_SSBO_COUNTERS, kCounters},     {CULLIDE_SSBO_ALIVE, kAlive},
        {CULLIDE_SSBO_ITEM_BOUNDS, kItemBounds}, {CULLIDE_SSBO_PRIM_BEGIN, kPrimBegin},
        {CULLIDE_SSBO_ITEM_PRIMS, kItemPrims},  {CULLIDE_SSBO_BANDS, kBands},
        {CULLIDE_SSBO_BUILD, kBuild},           {CULLIDE_SSBO_VIEWS, kViews},
        {CULLIDE_SSBO_RANGES, kRanges},         {CULLIDE_SSBO_PARENT_ALIVE, kParentAlive},
        {CULLIDE_SSBO_ORDERED, kOrdered}};
    for (const auto& [binding, buffer] : bindings)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffers[buffer]);
}

void LevelDevice::buildPass(int pass, std::size_t invocations, LevelStats& level, Stats& stats) const {
    glUniform1i(CULLIDE_LOC_PASS, pass);
    const std::size_t dispatches = dispatchAll(invocations, CULLIDE_LOC_PRIM_BASE);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    level.draws += dispatches;
    stats.draws += dispatches;
}

void LevelDevice::buildRecords(int iteration, bool withBounds, LevelStats& level, Stats& stats) {
    const std::size_t primCount = levelItems->primitiveCount();
    const std::size_t groups = (primCount + CULLIDE_COMPUTE_GROUP_SIZE - 1) / CULLIDE_COMPUTE_GROUP_SIZE;
    if (groups > kMaxBuildGroups)
        throw BackendError("a level of " + std::to_string(primCount) + " primitives is over the limit of " +
                           std::to_string(kMaxBuildGroups * CULLIDE_COMPUTE_GROUP_SIZE));
    const auto setUp = Clock::now();
    reserveRecords(primCount);
    const bool twoPasses = bands == CULLIDE_BANDS_SHORT && !(perBandEstimate > 0.0f);
    if (twoPasses)  // each primitive's footprint, between the two passes
        reserveBuffer(buffers[kBands], capacity[kBands], primCount * 4);
    reserveBuffer(buffers[kBuild], capacity[kBuild], (CULLIDE_BUILD_GROUPS + groups) * 4);
    // The build's atomic counters start at 0 (the dispatch block is rewritten by the build's last work group).
    const GLuint zero = 0;
    glClearNamedBufferSubData(buffers[kCounters], GL_R32UI, 4 * CULLIDE_DISPATCH_NEEDED,
                              4 * (CULLIDE_COUNTERS_SIZE - CULLIDE_DISPATCH_NEEDED), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &zero);
    glClearNamedBufferSubData(buffers[kBuild], GL_R32UI, 4 * CULLIDE_BUILD_FOOTPRINTS_DONE, 4, GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &zero);
    // Each item's records, counted by the build.
    glClearNamedBufferSubData(buffers[kItemBounds], GL_R32UI, static_cast<GLintptr>(levelItems->size() * 24),
                              static_cast<GLsizeiptr>(levelItems->size() * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    bindBuffers();
    useForIteration(buildProgram, iteration);
    glUniform1ui(CULLIDE_LOC_ITEM_COUNT, static_cast<GLuint>(levelItems->size()));
    glUniform1ui(CULLIDE_LOC_PRIM_COUNT, static_cast<GLuint>(primCount));
    glUniform1i(CULLIDE_LOC_BANDS, bands);
    glUniform1ui(CULLIDE_LOC_GROUPS, static_cast<GLuint>(groups));
    glUniform1ui(CULLIDE_LOC_CAPACITY, static_cast<GLuint>(recordCapacity));
    glUniform1ui(CULLIDE_LOC_MAX_GROUPS, static_cast<GLuint>(maxGroups));
    glUniform1i(CULLIDE_LOC_WITH_BOUNDS, withBounds ? 1 : 0);
    glUniform1i(CULLIDE_LOC_ONE_PRIM_EACH, onePrimEach ? 1 : 0);
    startTiming();
    if (twoPasses) {  // the pixels per band come from every primitive's footprint
        buildPass(CULLIDE_BUILD_PASS_FOOTPRINTS, primCount, level, stats);
        buildPass(CULLIDE_BUILD_PASS_APPEND, primCount, level, stats);
    } else {
        const float perBand = bands == CULLIDE_BANDS_SHORT ? perBandEstimate : float(CULLIDE_PIXELS_PER_INVOCATION);
        glUniform1f(CULLIDE_LOC_PER_BAND, perBand);
        buildPass(CULLIDE_BUILD_PASS_SINGLE, primCount, level, stats);
    }
    checkGlError("building a level's records");
    level.recordBuilds += 1;
    level.setupMs += msSince(setUp);
}

void LevelDevice::reserveRecords(std::size_t records) {
    recordCapacity = std::max<std::size_t>({recordCapacity, records, 64});
    reserveBuffer(buffers[kPrims], capacity[kPrims], recordCapacity * 16);
    reserveBuffer(buffers[kPrimsNext], capacity[kPrimsNext], recordCapacity * 16);
    if (settings.backend == Backend::Raster)
        reserveBuffer(buffers[kRecords], capacity[kRecords], 3 * recordCapacity * kRecordBytes);
}

void LevelDevice::growRecords(std::uint32_t needed, float approx) {
    if (!(approx <= kMaxRecords))  // also NaN
        throw BackendError("a level needs about " + std::to_string(approx) + " records, over the limit of " +
                           std::to_string(static_cast<std::size_t>(kMaxRecords)));
    const double want = std::max<double>(needed, approx) * 1.25 + 64.0;
    recordCapacity = static_cast<std::size_t>(std::min(want, kMaxRecords));
}

void LevelDevice::startTiming() {
    if (timing) return;
    timing = true;
    timedSpan = Clock::now();
    if (!hasTimers) return;
    if (spans == timers.size()) {
        timers.push_back(0);
        glGenQueries(1, &timers.back());
    }
    glBeginQuery(GL_TIME_ELAPSED, timers[spans++]);
}

void LevelDevice::endTiming() {
    if (!timing) return;
    if (hasTimers) glEndQuery(GL_TIME_ELAPSED);
    timing = false;
}

double LevelDevice::spanMs(std::size_t span, Clock::time_point opened) const {
    return hasTimers && span < spans ? timerResultMs(timers[span], msSince(opened)) : -1.0;
}

void LevelDevice::forgetSpans() {
    endTiming();
    spans = 0;
    uploadSpans.clear();
}

void LevelDevice::noteUploadSpans(Stats& stats) {
    for (const auto& [span, opened] : uploadSpans) recordUploadGpuTime(spanMs(span, opened), stats);
    uploadSpans.clear();
}

void LevelDevice::prepareIteration(std::size_t itemCount) {
    const GLuint empty[2] = {0xFFFFFFFFu, 0u};
    // The last iteration's image atomics before the clears (a texture update, which SHADER_IMAGE_ACCESS does not
    // order).
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
    glClearTexImage(images[CULLIDE_IMAGE_NEAR1], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[0]);
    glClearTexImage(images[CULLIDE_IMAGE_NEAR2], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[0]);
    glClearTexImage(images[CULLIDE_IMAGE_FAR1], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
    glClearTexImage(images[CULLIDE_IMAGE_FAR2], 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
    glClearNamedBufferSubData(buffers[kFlags], GL_R32UI, 0, static_cast<GLsizeiptr>(itemCount * 4),
                              GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
    // flag.comp's count of the invocations done per item
    glClearNamedBufferSubData(buffers[kItemBounds], GL_R32UI, static_cast<GLintptr>(itemCount * 28),
                              static_cast<GLsizeiptr>(itemCount * 4), GL_RED_INTEGER, GL_UNSIGNED_INT, &empty[1]);
    clearIterationCounters();
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

void LevelDevice::issueIteration(int iteration, LevelStats& level, Stats& stats) {
    const std::size_t itemCount = levelItems->size();
    startTiming();
    prepareIteration(itemCount);
    if (settings.backend == Backend::Raster) {
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_RECORDS, buffers[kRecords]);
        useForIteration(setupProgram, iteration);
        glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_CULL);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        level.draws += 1;
        stats.draws += 1;
    }
    useForIteration(program, iteration);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_PRIMS_OUT, buffers[kPrimsNext]);
    draw(CULLIDE_PASS_NEAREST, level, stats);
    if (settings.backend == Backend::Compute) {
        // The nearest pass packed the records of the items alive: the second and flag passes run over those, and
        // the flag pass ends the iteration.
        swapRecords();
        useForIteration(secondProgram, iteration);
        draw(CULLIDE_PASS_SECOND, level, stats);
        useForIteration(flagProgram, iteration);
        draw(CULLIDE_PASS_FLAG, level, stats);
        return;
    }
    draw(CULLIDE_PASS_SECOND, level, stats);
    draw(CULLIDE_PASS_FLAG, level, stats);
    useForIteration(surviveProgram, iteration);
    glDispatchComputeIndirect(4 * CULLIDE_DISPATCH_SURVIVE);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    level.draws += 1;
    stats.draws += 1;
    swapRecords();  // the records the survivor pass packed are the next iteration's
}

void LevelDevice::useForIteration(GLuint p, int iteration) const {
    glUseProgram(p);
    glUniform1ui(CULLIDE_LOC_ITERATION, static_cast<GLuint>(iteration));
}

void LevelDevice::swapRecords() {
    std::swap(buffers[kPrims], buffers[kPrimsNext]);
    std::swap(capacity[kPrims], capacity[kPrimsNext]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_PRIMS, buffers[kPrims]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_PRIMS_OUT, buffers[kPrimsNext]);
}

bool LevelDevice::readBack(GLuint buffer, std::size_t offset, std::size_t bytes, void* to, LevelStats& level,
                           Stats& stats, const Deadline& until) {
    const auto waitStart = Clock::now();
    const auto delayEnd = waitStart + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double, std::milli>(readBackDelayMs));
    level.blockingReadBacks += 1;
    stats.blockingReadBacks += 1;
    if (until && !waitForDeviceUntil(*until.at(), delayEnd)) {
        level.waitMs += msSince(waitStart);
        return false;
    }
    glGetNamedBufferSubData(buffer, static_cast<GLintptr>(offset), static_cast<GLsizeiptr>(bytes), to);
    if (readBackDelayMs > 0.0) std::this_thread::sleep_until(delayEnd);  // a slow device's round trip (tests)
    level.waitMs += msSince(waitStart);
    stats.bytesReadBack += bytes;
    noteUploadSpans(stats);  // the uploads before it are done too
    return true;
}

void LevelDevice::waitForChain(bool withAhead, LevelStats& level, Stats& stats) {
    const std::size_t words = counterWords(levelItems->size());
    endTiming();
    if (withAhead)
        glCopyNamedBufferSubData(buffers[kStash], buffers[kCounters], 0, 4 * CULLIDE_AHEAD, 4 * kChainWords);
    readScratch.resize(words);
    readBack(buffers[kCounters], 0, 4 * words, readScratch.data(), level, stats);
    recordGpuTime(spanMs(lastSpan(), timedSpan), level, stats);
    checkGlError("a level's visibility iterations");
}

int LevelDevice::issueLevel(const LevelItems& items, const LevelStart& start, int iterations, float perBand,
                           LevelStats& level, Stats& stats) {
    levelItems = &items;
    perBandEstimate = perBand;
    const auto send = Clock::now();
    uploadItems(items, start, level, stats);
    level.setupMs += msSince(send);
    buildRecords(0, true, level, stats);
    setLevelUniforms(start.coordinateBound);
    const int issued = std::min(settings.maxIterations, std::max(iterations, 1));
    for (int i = 0; i < issued; ++i) issueIteration(i, level, stats);
    return issued;
}

void survivorsFrom(const std::uint32_t* bits, std::size_t items, std::uint32_t stop,
                   std::vector<std::uint8_t>& survivors) {
    survivors.resize(items);
    const bool allPruned = stop == CULLIDE_STOP_ONE_OWNER;
    for (std::size_t i = 0; i < items; ++i)
        survivors[i] = static_cast<std::uint8_t>(allPruned ? 0u : (bits[i / 32] >> (i % 32)) & 1u);
}

void LevelDevice::readSurvivors(std::uint32_t stop, std::vector<std::uint8_t>& survivors) const {
    survivorsFrom(readScratch.data() + CULLIDE_ALIVE_BITS, levelItems->size(), stop, survivors);
}

void LevelDevice::readTrace(GLuint views, std::size_t first, int ran, std::vector<IterationTrace>& trace) {
    std::vector<ViewRecord> records(static_cast<std::size_t>(ran));
    glGetNamedBufferSubData(views, static_cast<GLintptr>(first * sizeof(ViewRecord)),
                            static_cast<GLsizeiptr>(records.size() * sizeof(ViewRecord)), records.data());
    for (const ViewRecord& r : records) trace.push_back(toTrace(r));
}

}  // namespace cullide::gl
