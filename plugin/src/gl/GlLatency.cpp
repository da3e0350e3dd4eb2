#include "cullide/GlLatency.h"

#include "cullide/Culler.h"
#include "cullide/Timer.h"
#include "gl/EglContext.h"
#include "gl/GlApi.h"
#include "gl/GlProgram.h"
#include "gl/GpuTimes.h"
#include "bindings.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace cullide {
namespace {

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// One dependent dispatch: the word the last one wrote, read and written again after a storage barrier.
void dispatchOnce() {
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    glDispatchCompute(1, 1, 1);
}

/// The GL objects of one measurement, deleted with it (the context goes last).
struct Probe {
    explicit Probe(const std::string& device) : context(device) {
        context.makeCurrent();
        program = gl::linkProgram(gl::Program::Probe);
        glCreateBuffers(1, &buffer);
        const GLuint zero = 0;
        glNamedBufferData(buffer, 4, &zero, GL_DYNAMIC_DRAW);
        glGenQueries(1, &query);
        glUseProgram(program);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, CULLIDE_SSBO_COUNTERS, buffer);
    }
    ~Probe() {
        if (!context.tryMakeCurrent()) return;
        glDeleteQueries(1, &query);
        glDeleteBuffers(1, &buffer);
        glDeleteProgram(program);
    }
    Probe(const Probe&) = delete;
    Probe& operator=(const Probe&) = delete;

    gl::EglContext context;
    GLuint program = 0;
    GLuint buffer = 0;
    GLuint query = 0;
};

}  // namespace

GlLatency measureGlLatency(const std::string& device, int dispatches, int roundTrips) {
    if (dispatches < 1 || roundTrips < 1) throw std::invalid_argument("measureGlLatency: counts must be at least 1");
    Probe probe(device);
    GlLatency result;
    result.renderer = probe.context.renderer();
    result.device = probe.context.device();
    result.dispatches = dispatches;
    result.roundTrips = roundTrips;
    // Warm up: the first dispatch may compile or upload, and a driver's first timer result may be nonsense
    // (llvmpipe's: an absolute time, GpuTimes.h).
    if (probe.context.hasTimerQueries()) glBeginQuery(GL_TIME_ELAPSED, probe.query);
    dispatchOnce();
    if (probe.context.hasTimerQueries()) {
        glEndQuery(GL_TIME_ELAPSED);
        GLuint64 ignored = 0;
        glGetQueryObjectui64v(probe.query, GL_QUERY_RESULT, &ignored);
    }
    glFinish();

    if (probe.context.hasTimerQueries()) glBeginQuery(GL_TIME_ELAPSED, probe.query);
    const Timer issued;
    for (int i = 0; i < dispatches; ++i) dispatchOnce();
    result.dispatchIssueUs = issued.ms() * 1e3 / dispatches;
    if (probe.context.hasTimerQueries()) glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    if (probe.context.hasTimerQueries()) {
        const double ms = gl::timerResultMs(probe.query, issued.ms());
        if (ms >= 0.0) result.dispatchDeviceUs = ms * 1e3 / dispatches;
    }

    std::vector<double> fences, readBacks;
    for (int i = 0; i < roundTrips; ++i) {
        dispatchOnce();
        GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        const Timer waiting;
        const GLenum waited = glClientWaitSync(fence, GL_SYNC_FLUSH_COMMANDS_BIT, GLuint64{10'000'000'000});
        fences.push_back(waiting.ms() * 1e3);
        glDeleteSync(fence);
        if (waited == GL_TIMEOUT_EXPIRED || waited == GL_WAIT_FAILED)
            throw gl::GlError("measureGlLatency: a fence did not signal");

        dispatchOnce();
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        GLuint word = 0;
        const Timer reading;
        glGetNamedBufferSubData(probe.buffer, 0, 4, &word);
        readBacks.push_back(reading.ms() * 1e3);
        // Every dispatch so far ran once: the warm-up, the batch and two per round trip.
        if (word != static_cast<GLuint>(1 + dispatches + 2 * (i + 1)))
            throw gl::GlError("measureGlLatency: the dispatches did not all run");
    }
    gl::checkGlError("measureGlLatency");
    result.fenceUs = median(fences);
    result.readBackUs = median(readBacks);
    return result;
}

}  // namespace cullide
