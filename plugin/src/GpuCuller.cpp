// The CULLIDE frame pipeline: validation and the CPU box pre-pass, triangle boxes and groups, the visibility levels
// (object, sub-object and triangle levels of image-space pruning, on a PruningBackend) or the CPU path, then the
// exact stage. Each stage is a function of the frame's state (FrameState.h), passed explicitly.
#include "AutoLevels.h"
#include "Deadline.h"
#include "CullerBackends.h"
#include "ExactStage.h"
#include "FrameObjects.h"
#include "FrameState.h"
#include "KeptCapacity.h"
#include "LevelPipelines.h"
#include "MeshCache.h"
#include "MeshTrees.h"
#include "PairAssembly.h"
#include "TriangleOrders.h"
#include "TriangleSets.h"
#include "WorldMeshes.h"
#include "exact/BoxTree.h"
#include "cullide/Culler.h"
#include "cullide/Timer.h"

#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>

namespace cullide {
namespace {

/// The one-line notice that a culler runs without GL: once per process and reason, not for every culler (the Bullet
/// adapter re-creates its culler when its margin must grow).
void noticeOnce(const std::string& reason) {
    static std::mutex mutex;
    static std::set<std::string> given;
    const std::lock_guard<std::mutex> lock(mutex);
    if (given.insert(reason).second)
        std::fprintf(stderr, "cullide: no usable GL device, running the CPU path (no GPU levels): %s\n", reason.c_str());
}

class GpuCuller final : public Culler {
public:
    /// `autoOnHardwareOnly`: GpuLevels::Auto opens no backend unless the selected device is a hardware one
    /// (createGpuCuller; a custom backend factory decides for itself).
    GpuCuller(const Settings& settings, const PruningBackendFactory& makeBackend, bool autoOnHardwareOnly)
        : m_settings(settings), m_pool(settings.threads), m_exact(m_pool) {
        openBackend(makeBackend, autoOnHardwareOnly);
    }

    const Settings& settings() const override { return m_settings; }

    void run(const std::vector<Object>& objects, Result& result) override { runFrame(objects, nullptr, result); }

    void run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& only, Result& result) override {
        checkPairList(only, objects.size());
        runFrame(objects, &only, result);
    }

    void run(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>& only, Result& result,
             double budgetMs) override {
        checkPairList(only, objects.size());
        runFrame(objects, &only, result, budgetMs);
    }

private:
    /// One frame: every overlapping pair, or only those listed in `only`.
    void runFrame(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>* only, Result& result,
                  double budgetMs = 0.0) {
        try {
            runStages(objects, only, result, Deadline::after(std::chrono::steady_clock::now(), budgetMs));
        } catch (const RunAbandoned&) {
            Stats stats = std::move(result.stats);
            result.clear();
            stats.abandoned = true;
            result.stats = std::move(stats);
            m_frame.objects = nullptr;
            m_frame.inputs = nullptr;
        }
    }

    /// The frame's stages; RunAbandoned from a stage that found `runDeadline` spent.
    void runStages(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>* only, Result& result,
                   const Deadline& runDeadline) {
        Timer total;
        const TaskPool::Busy busy(m_pool);  // workers woken now, polling through the frame's serial steps
        const TaskPool::Counters poolBefore = m_pool.counters();
        m_frame.surviving.swap(result.pcsTriangles);  // the lists handed out last frame: reused, capacity and all
        result.clear();
        Stats& stats = result.stats;
        stats.renderer = m_backend ? m_backend->renderer() : std::string();
        stats.device = m_backend ? m_backend->device() : std::string("none");
        stats.gpuUnavailable = m_gpuUnavailable;
        FrameState& frame = m_frame;

        const auto start = std::chrono::steady_clock::now();
        frame.runDeadline = runDeadline;
        Timer prepass;
        prepareObjects(objects, only, frame, result);
        const bool autoActive = choosePath(frame, start, stats);
        if (runDeadline.expired()) throw RunAbandoned{};
        prepareTriangles(objects, frame, stats);
        stats.prepassMs = prepass.ms();
        if (runDeadline.expired()) throw RunAbandoned{};

        Timer levels;
        if (!findSurvivingTriangles(frame, stats)) {
            // A GPU trial frame past its budget: finished on the CPU path (its time then makes the CPU path win).
            const Timer cpu;
            frame.gpuLevels = false;
            clearLists(frame.surviving, objects.size());
            prepareTriangles(objects, frame, stats);
            findSurvivingTriangles(frame, stats);
            stats.prepassMs += cpu.ms();
        }
        // Without GPU levels this stage is the CPU collection of the pre-pass's triangles: count it there.
        (frame.gpuLevels ? stats.gpuLevelsMs : stats.prepassMs) += levels.ms() - stats.uploadMs;

        if (runDeadline.expired()) throw RunAbandoned{};
        Timer exact;
        if (!frame.gpuLevels) stats.meshOrdersComputed += assignTreeOrders(objects, frame);
        m_assembly.run(frame, m_settings, m_exact, result);
        if (runDeadline.expired()) throw RunAbandoned{};  // some exact-stage tasks were skipped
        if (!frame.gpuLevels) m_trees.listPairedTriangles(result, frame, m_pool);
        stats.exactMs = exact.ms();
        stats.pcsObjects = result.pcs.size();
        stats.candidateObjectPairs = result.pairs.size();
        result.pcsTriangles.swap(frame.surviving);  // reassigned at the start of the next frame
        stats.gpuDeviceBytes = m_backend ? m_backend->deviceBytes() : 0;
        countPool(poolBefore, stats);
        stats.totalMs = total.ms();
        if (autoActive) recordAutoFrame(stats);
        frame.objects = nullptr;
        frame.inputs = nullptr;
    }

    void countPool(const TaskPool::Counters& before, Stats& stats) const {
        const TaskPool::Counters now = m_pool.counters();
        stats.poolCalls = now.calls - before.calls;
        stats.poolWorkerWakes = now.workerWakes - before.workerWakes;
        stats.poolCallerSleeps = now.callerSleeps - before.callerSleeps;
    }

    /// The CPU box pre-pass: validation (static meshes' kept from earlier frames), the overlapping object pairs
    /// (all, or those of `only`), the objects that take part in one (active), and world-space meshes for those.
    void prepareObjects(const std::vector<Object>& objects, const std::vector<ObjectIndexPair>* only,
                        FrameState& frame, Result& result) {
        Stats& stats = result.stats;
        m_statics.lookUp(objects, frame.statics);
        frame.valid = validateObjects(objects, m_settings.margin, result.rejected, &m_pool, &frame.statics.known);
        StaticMeshCache::merge(objects, frame.statics, m_settings.margin, frame.valid, result, stats);
        stats.objects = objects.size();
        stats.rejectedObjects = result.rejected.size();
        for (std::size_t i = 0; i < objects.size(); ++i) {
            if (frame.valid[i].valid && frame.valid[i].isMesh) stats.triangles += objects[i].mesh->triangles.size();
            if (frame.valid[i].valid) ++stats.prepassObjectsIn;
        }
        frame.pairs = only != nullptr ? listedOverlappingPairs(frame.valid, *only) : overlappingPairs(frame.valid);
        clearLists(frame.partners, objects.size());
        for (const auto& [a, b] : frame.pairs) {
            frame.partners[a].push_back(b);
            frame.partners[b].push_back(a);
        }
        // Only objects whose box meets another's can collide (both pipelines): the views are fitted to the groups
        // that can meet (clusters, LevelPipelines), never to a far outlier.
        frame.active.assign(objects.size(), 0);
        for (std::size_t i = 0; i < objects.size(); ++i) {
            frame.active[i] = frame.partners[i].empty() ? 0 : 1;
            stats.prepassObjectsOut += frame.active[i];
        }
        frame.inputs = &objects;
        frame.objects = &m_world.resolve(objects, frame.active, &m_pool);
        clearLists(frame.surviving, objects.size());
    }

    /// Sets frame.gpuLevels: whether this frame runs the visibility levels (a backend is there): always in the
    /// paper pipeline and with GpuLevels::Always; with GpuLevels::Auto, as AutoLevels decides from timing both
    /// paths on this scene. Returns whether the choice was AutoLevels' (the frame's time is then recorded).
    bool choosePath(FrameState& frame, std::chrono::steady_clock::time_point start, Stats& stats) {
        frame.gpuLevels = false;
        frame.levelsDeadline = Deadline();
        if (!m_backend) return false;
        const bool autoActive = m_settings.pipeline != Pipeline::Paper && m_settings.gpuLevels == GpuLevels::Auto;
        if (!autoActive) {
            frame.gpuLevels = m_settings.pipeline == Pipeline::Paper || m_settings.gpuLevels == GpuLevels::Always;
            return false;
        }
        std::size_t triangles = 0;
        for (std::uint32_t i = 0; i < frame.active.size(); ++i)
            if (frame.isActiveMesh(i)) triangles += frame.meshOf(i).triangles.size();
        m_autoPath = m_auto.choose(triangles);
        stats.autoDecision = m_auto.decision();
        frame.gpuLevels = m_autoPath == AutoLevels::Path::Gpu;
        frame.levelsDeadline = Deadline::after(start, m_auto.trialBudgetMs());
        return true;
    }

    /// The triangles' orders, boxes and groups for the path frame.gpuLevels says.
    void prepareTriangles(const std::vector<Object>& objects, FrameState& frame, Stats& stats) {
        assignOrders(objects, frame, stats);
        buildTriangleBoxesAndGroups(frame, static_cast<std::uint32_t>(m_settings.groupSize), m_settings.margin,
                                    m_settings.pipeline != Pipeline::Paper, m_pool, m_scratch, stats);
    }

    /// The meshes' kept spatial orders needed before the triangle stages: every active mesh's with GPU levels (their
    /// groups follow it); on the CPU path, which meshes get a whole tree (MeshTrees) and the orders of those built
    /// now.
    void assignOrders(const std::vector<Object>& objects, FrameState& frame, Stats& stats) {
        m_orders.beginFrame(objects.size(), frame);
        if (frame.gpuLevels) {
            frame.whole.assign(objects.size(), 0);
            frame.tree.assign(objects.size(), nullptr);
            stats.meshOrdersComputed = m_orders.assign(objects, frame, [](std::uint32_t) { return true; }, m_pool);
            return;
        }
        MeshTrees::choose(frame);
        stats.meshOrdersComputed = m_orders.assign(
            objects, frame, [&](std::uint32_t o) { return MeshTrees::needsBuild(frame, o); }, m_pool);
    }

    /// frame.surviving (with the survivors' boxes): by the visibility levels, or by the CPU path. A backend error
    /// mid-frame costs this frame its pruning, never a contact: every triangle that the CPU pre-pass keeps goes to the
    /// exact stage. False when the levels ran past the frame's levelsDeadline: the caller finishes the frame on the
    /// CPU path.
    bool findSurvivingTriangles(FrameState& frame, Stats& stats) {
        if (!frame.gpuLevels) {
            if (frame.runDeadline.expired()) throw RunAbandoned{};
            m_trees.build(frame, m_settings.margin, m_pool, stats);
            if (frame.runDeadline.expired()) throw RunAbandoned{};
            collectDirect(frame, static_cast<std::uint32_t>(m_settings.groupSize), m_settings.margin, m_pool,
                          m_scratch);
            return true;
        }
        try {
            m_levels.run(frame, m_settings, *m_backend, m_pool, m_scratch, stats);
        } catch (const LevelsAbandoned&) {
            ++stats.autoTrialsAbandoned;
            stats.levels.clear();
            return false;
        } catch (const BackendError& e) {
            ++stats.gpuFallbacks;
            stats.gpuError = e.what();
            m_backend->forgetUploads();  // what the device holds is no longer trusted, its exact pairs included
            frame.devicePairs.clear();
            frame.exactOnDevice.assign(frame.valid.size(), 0);
            clearLists(frame.surviving, frame.valid.size());
            collectTriangles(frame, frame.groups, m_settings.pipeline != Pipeline::Paper, m_settings.margin, m_pool,
                             m_scratch, m_fallbackTriangles);
            addSurvivingTriangles(frame, m_fallbackTriangles, {});
        }
        computeSurvivorBoxes(frame, m_settings.margin, m_pool, m_scratch);
        return true;
    }

    /// The CPU path: kept spatial orders for the meshes (without a whole tree) whose surviving triangles are enough
    /// of them for their box trees to follow the order (BoxTree::kOrderedFraction) instead of sorting.
    std::size_t assignTreeOrders(const std::vector<Object>& objects, FrameState& frame) {
        return m_orders.assign(objects, frame, [&](std::uint32_t o) {
            return !frame.hasWholeTree(o) &&
                   frame.surviving[o].size() * BoxTree::kOrderedFraction >= frame.meshOf(o).triangles.size();
        }, m_pool);
    }

    /// A frame that fell back to the CPU path after a backend error is no timing of the GPU levels: not recorded.
    void recordAutoFrame(Stats& stats) {
        if (stats.gpuFallbacks == 0) m_auto.record(m_autoPath, stats.totalMs);
        stats.autoDecision = m_auto.decision();
        stats.autoCpuMs = m_auto.cpuMs();
        stats.autoGpuMs = m_auto.gpuMs();
    }

    /// The pruning backend (the GL visibility pass in production), unless GPU levels are off (GpuLevels::Never: no
    /// EGL at all). Without a usable GL device the CPU path runs instead, with a one-line notice — unless GPU levels
    /// were demanded (GpuLevels::Always, Pipeline::Paper): then GlUnavailableError.
    void openBackend(const PruningBackendFactory& makeBackend, bool autoOnHardwareOnly) {
        if (m_settings.gpuLevels == GpuLevels::Never) {
            m_gpuUnavailable = "GPU levels off (GpuLevels::Never): no GL context opened";
            return;
        }
        const bool autoLevels = m_settings.gpuLevels == GpuLevels::Auto && m_settings.pipeline != Pipeline::Paper;
        if (autoOnHardwareOnly && autoLevels && !hasHardwareGlDevice(m_settings.device)) {
            m_gpuUnavailable = "GpuLevels::Auto runs GPU levels on hardware devices only, and the selected GL device "
                               "is not one: no GL context opened";
            return;
        }
        try {
            m_backend = makeBackend(m_settings);
        } catch (const GlUnavailableError& e) {
            const bool demanded = m_settings.gpuLevels == GpuLevels::Always || m_settings.pipeline == Pipeline::Paper;
            if (demanded) throw;
            m_backend.reset();
            m_gpuUnavailable = e.what();
            noticeOnce(m_gpuUnavailable);
        }
    }

    const Settings m_settings;
    TaskPool m_pool;  ///< before m_exact, which runs on it
    ExactStage m_exact;
    std::unique_ptr<PruningBackend> m_backend;  ///< null: no GPU levels (see openBackend)
    std::string m_gpuUnavailable;               ///< why there is no backend (Stats::gpuUnavailable)

    // What carries over between frames.
    StaticMeshCache m_statics;
    TriangleOrders m_orders;  ///< spatial orders of the meshes, kept between frames
    MeshTrees m_trees;        ///< the CPU path's trees of whole meshes (static meshes' are kept in m_statics)
    LevelPipelines m_levels;  ///< holds the device's copy of the geometry and its resident region
    AutoLevels m_auto;        ///< GpuLevels::Auto: the timing trial and its decision
    AutoLevels::Path m_autoPath = AutoLevels::Path::Cpu;  ///< the path AutoLevels chose for this frame

    // Per-frame state and working memory, kept only to reuse their allocations.
    FrameState m_frame;
    WorldMeshes m_world;  ///< world-space meshes of this frame's active objects that come with a transform
    TriangleScratch m_scratch;
    PairAssembly m_assembly;
    std::vector<FrameTriangle> m_fallbackTriangles;
};

}  // namespace

std::unique_ptr<Culler> createGpuCuller(const Settings& settings, const PruningBackendFactory& makeBackend) {
    const std::string error = settings.validate();
    if (!error.empty()) throw std::invalid_argument("cullide::Settings: " + error);
    return std::make_unique<GpuCuller>(settings, makeBackend, false);
}

std::unique_ptr<Culler> createGpuCuller(const Settings& settings) {
    const std::string error = settings.validate();
    if (!error.empty()) throw std::invalid_argument("cullide::Settings: " + error);
    return std::make_unique<GpuCuller>(settings, [](const Settings& s) { return createGlPruningBackend(s); }, true);
}

}  // namespace cullide
