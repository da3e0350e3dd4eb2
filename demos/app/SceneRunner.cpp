#include "SceneRunner.h"

#include "cullide/Timer.h"
#include "cullide/demo/BreakableScene.h"
#include "cullide/scenes/Environments.h"
#include "cullide/scenes/Procedural.h"

#include <algorithm>
#include <set>
#include <stdexcept>
#include <tuple>

namespace cullide::demo {

namespace {

std::vector<Object> asObjects(const std::vector<TriangleMesh>& meshes) {
    std::vector<Object> objects(meshes.size());
    for (std::size_t i = 0; i < meshes.size(); ++i) objects[i].mesh = &meshes[i];
    return objects;
}

std::set<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>> flatPairs(const Result& r) {
    std::set<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>> out;
    for (const ObjectPair& p : r.pairs)
        for (const TrianglePair& t : p.triangles) out.emplace(p.a, t.a, p.b, t.b);
    return out;
}

/// Reference triangle pairs missing from `result`, or whose triangles are missing from its triangle-level PCS.
long missedPairs(const Result& reference, const Result& result) {
    const auto got = flatPairs(result);
    auto inPcs = [&](std::uint32_t o, std::uint32_t t) {
        if (o >= result.pcsTriangles.size()) return false;
        return std::binary_search(result.pcsTriangles[o].begin(), result.pcsTriangles[o].end(), t);
    };
    long missed = 0;
    for (const auto& p : flatPairs(reference)) {
        const auto& [a, ta, b, tb] = p;
        if (!got.count(p) || !inPcs(a, ta) || !inPcs(b, tb)) ++missed;
    }
    return missed;
}

/// The potentially colliding set level by level: "name:in>out" per GPU level.
std::string levelSizes(const Stats& s) {
    std::string out;
    for (const LevelStats& level : s.levels) {
        if (level.itemsPerIteration.empty()) continue;
        if (!out.empty()) out += ' ';
        out += level.name + ':' + std::to_string(level.itemsPerIteration.front()) + '>' +
               std::to_string(level.itemsPerIteration.back());
    }
    return out;
}

/// The culler's set sizes and stage times (the caller sets the triangle pairs and frame times it knows better).
void fillFromStats(FrameRecord& r, const Stats& s, std::size_t pcsTriangles) {
    r.path = s.abandoned ? "abandoned" : s.levels.empty() ? "cpu-path" : "gpu-levels";
    r.levels = levelSizes(s);
    r.prepassObjects = s.prepassObjectsOut;
    r.prepassGroups = s.prepassGroupsOut;
    r.pcsObjects = s.pcsObjects;
    r.pcsTriangles = pcsTriangles;
    r.candidatePairs = s.candidateTrianglePairs;
    r.prepassMs = s.prepassMs;
    r.gpuLevelsMs = s.gpuLevelsMs + s.uploadMs;
    r.exactMs = s.exactMs;
    r.cullMs = s.totalMs;
}

/// env1 / env2 / env3: the culler on the environment's frames; the frame time is the culler's.
class EnvironmentRunner final : public SceneRunner {
public:
    explicit EnvironmentRunner(const RunnerOptions& o) : m_culler(createGpuCuller(o.culler)) {
        m_reference = createReferenceCuller(o.culler);
        if (o.scene == "env1") {
            m_env = scenes::makeEnv1(o.seed, o.objects > 0 ? o.objects : 100);
            m_defaultFrames = 100;
        } else if (o.scene == "env2") {
            m_env = scenes::makeEnv2(o.seed, o.objects > 0 ? o.objects : 6);
            m_defaultFrames = 30;
        } else {
            m_env = scenes::makeEnv3(scenes::defaultDataDir(), false, &m_standIns);
            m_defaultFrames = 60;
        }
    }

    FrameRecord advance(bool check) override {
        FrameRecord r;
        r.frame = m_frame;
        m_meshes = m_env->frame(m_frame++);
        const std::vector<Object> objects = asObjects(m_meshes);
        m_culler->run(objects, m_result);
        std::size_t pcsTriangles = 0;
        for (const auto& list : m_result.pcsTriangles) pcsTriangles += list.size();
        fillFromStats(r, m_result.stats, pcsTriangles);
        r.triangles = m_result.stats.triangles;
        r.trianglePairs = m_result.stats.intersectingTrianglePairs;
        r.objects = m_meshes.size();
        r.frameMs = m_result.stats.totalMs;
        if (check) {
            Result reference;
            m_reference->run(objects, reference);
            r.missed = missedPairs(reference, m_result);
        }
        return r;
    }
    const std::vector<TriangleMesh>& meshes() override { return m_meshes; }
    std::vector<std::string> names() const override {
        std::vector<std::string> n;
        for (std::size_t i = 0; i < m_meshes.size(); ++i) n.push_back(m_env->name() + "." + std::to_string(i));
        return n;
    }
    const Result& cullResult() override { return m_result; }
    std::string renderer() const override { return m_result.stats.renderer; }
    std::string device() const override { return m_result.stats.device; }
    bool usedStandIns() const override { return m_standIns; }
    int defaultFrames() const override { return m_defaultFrames; }

private:
    std::unique_ptr<Culler> m_culler;
    std::unique_ptr<Culler> m_reference;
    std::unique_ptr<scenes::Environment> m_env;
    std::vector<TriangleMesh> m_meshes;
    Result m_result;
    int m_frame = 0;
    int m_defaultFrames = 60;
    bool m_standIns = false;
};

/// The breakable Bullet scene. The frame's figures come from the CULLIDE broadphase and dispatcher; snapshots
/// and checks use a culler with the same settings on the bodies' world-space meshes.
class BreakableRunner final : public SceneRunner {
public:
    explicit BreakableRunner(const RunnerOptions& o) : m_scene(makeOptions(o)), m_settings(o.culler) {}

    FrameRecord advance(bool check) override {
        FrameRecord r;
        std::vector<std::pair<std::string, std::string>> expectedPairs;
        long missed = 0;
        if (check) {
            // The broadphase of the coming step sees the current state: every body pair that intersects now must
            // be among its pairs, and the culler must find every triangle pair of the current meshes.
            const std::vector<TriangleMesh> before = m_scene.worldMeshes();
            const std::vector<std::string> names = m_scene.bodyNames();
            const std::vector<Object> objects = asObjects(before);
            Result reference, result;
            referenceCuller().run(objects, reference);
            culler().run(objects, result);
            missed += missedPairs(reference, result);
            for (const ObjectPair& p : reference.pairs)
                if (!p.triangles.empty())
                    expectedPairs.emplace_back(std::min(names[p.a], names[p.b]), std::max(names[p.a], names[p.b]));
        }
        const BreakableFrame& f = m_scene.step();
        m_fresh = false;
        r.frame = f.frame;
        r.objects = f.bodies;
        r.triangles = f.triangles;
        fillFromStats(r, f.cullide.culler, f.cullide.pcsTriangles);
        if (f.cullide.culledPairs == 0) r.path = "not-culled";
        r.culledPairs = f.cullide.culledPairs;
        r.prunedPairs = f.cullide.prunedPairs;
        r.trianglePairs = f.trianglePairs;
        r.broadphasePairs = f.broadphasePairs;
        r.contacts = f.contacts;
        r.newPieces = f.brokenPieces;
        r.cullMs = f.broadphaseMs;  // the whole broadphase step (frame building, culler, pair cache)
        r.narrowphaseMs = f.narrowphaseMs;
        r.solverMs = f.solverMs;
        r.fractureMs = f.fractureMs;
        r.frameMs = f.totalMs;
        if (check) {
            const auto& got = m_scene.lastStepPairs();
            for (const auto& p : expectedPairs)
                if (!std::binary_search(got.begin(), got.end(), p)) ++missed;
            r.missed = missed;
        }
        return r;
    }

    const std::vector<TriangleMesh>& meshes() override {
        refresh();
        return m_meshes;
    }
    std::vector<std::string> names() const override { return m_scene.bodyNames(); }
    const Result& cullResult() override {
        refresh();
        return m_result;
    }
    std::optional<TriangleMesh> ground() const override {
        TriangleMesh g = scenes::makeBox(Vec3(2.2, 0.01, 1.6));
        scenes::transformMesh(g, Eigen::Affine3d(Eigen::Translation3d(0, -0.01, 0)));
        return g;
    }
    std::string renderer() const override {
        return m_result.stats.renderer.empty() ? m_scene.lastFrame().cullide.culler.renderer : m_result.stats.renderer;
    }
    std::string device() const override { return m_scene.lastFrame().cullide.culler.device; }
    bool usedStandIns() const override { return m_scene.usedStandIns(); }
    int fractures() const override { return m_scene.fractures(); }
    std::optional<CullingDecision> cullingDecision() const override {
        const CullideBroadphase* bp = m_scene.cullideBroadphase();
        if (bp == nullptr) return std::nullopt;
        return bp->getCullingDecision(CulledKind::GImpactPair);
    }
    int defaultFrames() const override { return 150; }

private:
    static BreakableOptions makeOptions(const RunnerOptions& o) {
        BreakableOptions b;
        b.seed = o.seed;
        b.culler = o.culler;
        b.fallingMesh = o.mesh;
        b.breakableMesh = o.breakableMesh;
        b.deepPenetrationFallback = o.deepPenetrationFallback;
        b.culling = o.culling;
        if (o.pipeline == "bullet-dbvt") b.pipeline = CollisionPipeline::BulletDbvt;
        else if (o.pipeline == "bullet-axis-sweep") b.pipeline = CollisionPipeline::BulletAxisSweep;
        else if (o.pipeline != "cullide") throw std::invalid_argument("unknown pipeline '" + o.pipeline + "'");
        return b;
    }

    void refresh() {
        if (m_fresh) return;
        m_meshes = m_scene.worldMeshes();
        culler().run(asObjects(m_meshes), m_result);
        m_fresh = true;
    }

    /// Made on first use: with --pipeline bullet-* and neither checks nor snapshots the demo needs no GL.
    Culler& culler() {
        if (!m_culler) m_culler = createGpuCuller(m_settings);
        return *m_culler;
    }
    Culler& referenceCuller() {
        if (!m_reference) m_reference = createReferenceCuller(m_settings);
        return *m_reference;
    }

    BreakableScene m_scene;
    Settings m_settings;
    std::unique_ptr<Culler> m_culler;
    std::unique_ptr<Culler> m_reference;
    std::vector<TriangleMesh> m_meshes;
    Result m_result;
    bool m_fresh = false;
};

}  // namespace

std::unique_ptr<SceneRunner> makeSceneRunner(const RunnerOptions& options) {
    if (options.scene == "breakable") return std::make_unique<BreakableRunner>(options);
    if (options.scene == "env1" || options.scene == "env2" || options.scene == "env3")
        return std::make_unique<EnvironmentRunner>(options);
    throw std::invalid_argument("unknown scene '" + options.scene + "' (breakable, env1, env2, env3)");
}

}  // namespace cullide::demo
