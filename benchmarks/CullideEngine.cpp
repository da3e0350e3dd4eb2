#include "CullideEngine.h"

#include "cullide/Timer.h"

namespace cullide::bench {

namespace {

const char* gpuLevelsName(GpuLevels g) {
    switch (g) {
        case GpuLevels::Always: return "always";
        case GpuLevels::Never: return "never";
        case GpuLevels::Auto: break;
    }
    return "auto";
}

}  // namespace

CullideEngine::CullideEngine(const Settings& settings, Kind kind) : m_settings(settings), m_kind(kind) {}

void CullideEngine::setup(const BenchFrame& first) {
    m_culler = m_kind == Kind::Exact                 ? createReferenceCuller(m_settings)
               : m_kind == Kind::VisibilityReference ? createVisibilityReferenceCuller(m_settings)
                                                     : createGpuCuller(m_settings);
    m_objects.assign(first.world->size(), Object{});
    for (std::size_t i = 0; i < m_objects.size(); ++i) {
        // Geometry that never changes in its own frame is keyed (the API's staticKey): the culler keeps a static
        // mesh's validation and triangle boxes between frames, and a rigid one's validation and group boxes in its
        // own frame.
        const Motion motion = (*first.motion)[i];
        if (motion == Motion::Static || motion == Motion::Rigid) m_objects[i].staticKey = i + 1;
    }
}

void CullideEngine::run(const BenchFrame& frame, FrameOutput& out) {
    out.clear();
    // A rigid object goes as Bullet's does: its mesh in its own frame and its pose (Object::transform).
    m_transforms.resize(m_objects.size());
    for (std::size_t i = 0; i < m_objects.size(); ++i) {
        const bool rigid = (*frame.motion)[i] == Motion::Rigid;
        m_objects[i].mesh = rigid ? &(*frame.local)[i] : &(*frame.world)[i];
        m_objects[i].transform = rigid ? &m_transforms[i] : nullptr;
        if (rigid) {
            m_transforms[i].linear = frame.poses[i].linear();
            m_transforms[i].translation = frame.poses[i].translation();
        }
    }
    const Timer timer;
    m_culler->run(m_objects, m_result);
    out.totalMs = timer.ms();
    const Stats& s = m_result.stats;
    if (m_kind == Kind::Exact) {
        out.stages = {{"brute force", out.totalMs}};
    } else {
        const double other = out.totalMs - s.prepassMs - s.uploadMs - s.gpuLevelsMs - s.exactMs;
        out.stages = {{"pre-pass", s.prepassMs},
                      {"upload", s.uploadMs},
                      {"gpu levels", s.gpuLevelsMs},
                      {"exact", s.exactMs},
                      {"other", other > 0.0 ? other : 0.0}};
        out.candidates = s.candidateTrianglePairs;
    }
    out.bytesUploaded = s.bytesUploaded;
    out.bytesReadBack = s.bytesReadBack;
    out.gpuDeviceBytes = s.gpuDeviceBytes;
    out.draws = s.draws;
    out.blockingReadBacks = s.blockingReadBacks;
    // The levels' device time (the uploads' is in Stats::gpuMs too since it is timed: kept apart here, as the
    // results of earlier runs have it).
    if (s.gpuTimingValid && !s.levels.empty()) out.gpuTimerMs = s.gpuMs - s.uploadGpuMs;
    out.pool = std::array<std::size_t, 3>{s.poolCalls, s.poolWorkerWakes, s.poolCallerSleeps};
    out.levels = nlohmann::json::array();
    for (const LevelStats& l : s.levels) {
        nlohmann::json level = {{"name", l.name}, {"items", l.itemsPerIteration}, {"draws", l.draws},
                                {"cpu_ms", l.cpuMs}, {"setup_ms", l.setupMs}, {"setup_send_ms", l.setupSendMs},
                                {"iterations", l.iterations}, {"records", l.records},
                                {"record_builds", l.recordBuilds}, {"short_builds", l.shortBuilds},
                                {"idle_iterations", l.idleIterations},
                                {"blocking_read_backs", l.blockingReadBacks}, {"deferred", l.deferred},
                                {"wait_ms", l.waitMs}};
        if (l.gpuTimingValid) {
            level["gpu_ms"] = l.gpuMs;
            level["exact_gpu_ms"] = l.exactGpuMs;
        }
        out.levels.push_back(level);
    }
    for (const ObjectPair& p : m_result.pairs) {
        if (!p.hasTriangles) continue;
        for (const TrianglePair& t : p.triangles) out.pairs.addTriangle(p.a, t.a, p.b, t.b);
    }
    out.pairs.finish();
}

nlohmann::json CullideEngine::describe() const {
    nlohmann::json j;
    if (m_kind == Kind::Exact) {
        j["mode"] = "exact";
        j["threads"] = m_settings.threads;
        j["renderer"] = "cpu-reference";
        return j;
    }
    j["mode"] = m_settings.mode == Mode::Reliable ? "reliable" : "sampled";
    j["resolution"] = m_settings.resolution;
    j["gpu_levels"] = gpuLevelsName(m_settings.gpuLevels);
    j["group_size"] = m_settings.groupSize;
    j["max_iterations"] = m_settings.maxIterations;
    j["min_prune_fraction"] = m_settings.minPruneFraction;
    j["threads"] = m_settings.threads;
    j["renderer"] = m_result.stats.renderer;
    j["device"] = m_result.stats.device;
    if (!m_result.stats.autoDecision.empty()) {  // GpuLevels::Auto: its decision after the last frame, and why
        j["auto_decision"] = m_result.stats.autoDecision;
        j["auto_cpu_ms"] = m_result.stats.autoCpuMs;
        j["auto_gpu_ms"] = m_result.stats.autoGpuMs;
    }
    return j;
}

}  // namespace cullide::bench
