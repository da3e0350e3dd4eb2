// cullide-trial-bench: what the Auto trials cost a frame loop (the worst frame against the median).
//
//   cullide-trial-bench [--frames N] [--json FILE]
//
// Culler: a program that makes a culler with the default settings (createGpuCuller(Settings{}), GpuLevels::Auto)
// for every frame of env1 frame 30 and env3 frame 0 with object 0 nudged each frame — every frame is a new
// culler's first, so it is where Auto's trial would run — and a program that keeps one culler for all frames. The
// swap: a collision world of GImpact tori stepped with the broadphase's defaults (Culling::Auto), and
// the same with Auto trialled anywhere (setAutoCullingOnAnyDevice), each in lockstep with a world whose switches are
// Off (the same states every step), so that a step's extra cost is the trial's. Each row: the median and worst frame
// or step, and whether the worst stays within 2x the median + 1 ms.
#include "BulletMesh.h"
#include "cullide/Culler.h"
#include "cullide/Timer.h"
#include "cullide/scenes/Environments.h"
#include "cullide_bullet/CullideBroadphase.h"
#include "cullide_bullet/CullideCollisionDispatcher.h"

#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace {

struct Row {
    std::string what;
    std::vector<double> ms;
    std::string note;
    /// Set for a row of per-step extra costs (a trial's step less the same step without it): bounded when the
    /// largest stays within `extraBound` (the trial world's median step + 1 ms: the step then costs at most about
    /// twice its median + 1 ms).
    double extraBound = -1.0;
    double median() const {
        std::vector<double> v = ms;
        std::sort(v.begin(), v.end());
        return v.empty() ? 0.0 : v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    }
    double worst() const { return ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end()); }
    /// The worst frame or step after the first (which also makes the culler and warms its kept state).
    double worstAfterFirst() const { return ms.size() < 2 ? 0.0 : *std::max_element(ms.begin() + 1, ms.end()); }
    /// Which frame or step was the worst (0: the first, which also makes the culler or the worlds).
    std::size_t worstAt() const {
        return ms.empty() ? 0 : static_cast<std::size_t>(std::max_element(ms.begin(), ms.end()) - ms.begin());
    }
    bool bounded() const { return extraBound >= 0.0 ? worst() <= extraBound : worst() <= 2.0 * median() + 1.0; }
};

/// The culler on one environment frame, object 0 nudged by `nudge` per frame; a new culler every frame, or one.
Row cullerFrames(const std::string& env, int envFrame, int frames, bool newCullerEveryFrame) {
    std::unique_ptr<cullide::scenes::Environment> e =
        env == "env1" ? cullide::scenes::makeEnv1(1) : cullide::scenes::makeEnv3(cullide::scenes::defaultDataDir(), false);
    std::vector<cullide::TriangleMesh> meshes = e->frame(envFrame);
    Row row{env + " frame " + std::to_string(envFrame) + (newCullerEveryFrame ? ", a new culler every frame" : ", one culler"),
            {}, {}, -1.0};
    std::unique_ptr<cullide::Culler> kept;
    for (int f = 0; f < frames; ++f) {
        for (cullide::Vec3& v : meshes[0].vertices) v.x() += 1e-4;
        std::vector<cullide::Object> objects(meshes.size());
        for (std::size_t i = 0; i < meshes.size(); ++i) objects[i].mesh = &meshes[i];
        cullide::Result result;
        const cullide::Timer t;
        if (newCullerEveryFrame || !kept) kept = cullide::createGpuCuller(cullide::Settings{});
        kept->run(objects, result);
        row.ms.push_back(t.ms());
        row.note = result.stats.autoDecision.empty() ? result.stats.gpuUnavailable : "auto: " + result.stats.autoDecision;
    }
    return row;
}

/// A GImpact torus mesh of margin `margin` (the arrays live as long as the returned holder).
struct TorusMesh {
    std::vector<btScalar> v;
    std::vector<int> idx;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btGImpactMeshShape> shape;
    TorusMesh(double R, double r, int segments, int sides, double margin) {
        cullide::bench::torusArrays(R, r, segments, sides, v, idx);
        array = std::make_unique<btTriangleIndexVertexArray>(int(idx.size() / 3), idx.data(), int(3 * sizeof(int)),
                                                             int(v.size() / 3), v.data(), int(3 * sizeof(btScalar)));
        shape = std::make_unique<btGImpactMeshShape>(array.get());
        shape->setMargin(btScalar(margin));
        shape->updateBound();
    }
};

/// A collision world (Bullet as a collision library) of 64 GImpact tori in a lattice, each touching its neighbours,
/// through the swap with the broadphase's default switches (Culling::Auto): every step the tori turn a little
/// (the same motion in every world), so each step costs about the same.
struct SwapWorld {
    btDefaultCollisionConfiguration config;
    cullide::CullideBroadphase broadphase;
    cullide::CullideCollisionDispatcher dispatcher{&config, &broadphase};
    btCollisionWorld world{&dispatcher, &broadphase, &config};
    std::vector<std::unique_ptr<btCollisionObject>> objects;

    SwapWorld(btCollisionShape* torus, bool autoAnywhere, cullide::Culling culling) {
        broadphase.setAutoCullingOnAnyDevice(autoAnywhere);
        broadphase.setGImpactPairCulling(culling);
        btGImpactCollisionAlgorithm::registerAlgorithm(&dispatcher);
        for (int i = 0; i < 64; ++i) {
            objects.push_back(std::make_unique<btCollisionObject>());
            objects.back()->setCollisionShape(torus);
            objects.back()->setWorldTransform(placement(i, 0));
            world.addCollisionObject(objects.back().get());
        }
    }
    ~SwapWorld() {
        for (auto& o : objects) world.removeCollisionObject(o.get());
    }
    static btTransform placement(int i, int step) {
        const btQuaternion q(btVector3(btScalar(0.3 * (i % 3)), 1, btScalar(0.2 * (i % 2))).normalized(),
                             btScalar(i + 0.01 * step));
        return btTransform(q, btVector3(btScalar(2.4 * (i % 4)), btScalar(2.4 * ((i / 4) % 4)), btScalar(2.4 * (i / 16))));
    }
    double step(int s) {
        for (std::size_t i = 0; i < objects.size(); ++i) objects[i]->setWorldTransform(placement(int(i), s));
        const cullide::Timer t;
        world.performDiscreteCollisionDetection();
        return t.ms();
    }
};

/// The swap's steps with the default switches against the same steps with culling Off (the old default), in
/// lockstep (the same placements every step, the order of the two alternating). `autoAnywhere`: Auto trials here.
std::vector<Row> swapSteps(int steps, bool autoAnywhere) {
    TorusMesh torus(1.0, 0.3, 32, 16, 0.02);
    SwapWorld off(torus.shape.get(), false, cullide::Culling::Off);
    SwapWorld automatic(torus.shape.get(), autoAnywhere, cullide::Culling::Auto);
    const std::string what = std::string("swap, 64 GImpact tori in a lattice, ") +
                             (autoAnywhere ? "Auto trialled anywhere" : "default switches");
    Row autoRow{what, {}, {}, -1.0}, offRow{"  ... the same steps with every switch Off", {}, {}, -1.0};
    Row extraRow{"  ... Auto's step less Off's, per step (bound: Auto's median + 1 ms)", {}, {}, -1.0};
    for (int s = 0; s < steps; ++s) {
        double a = 0, o = 0;
        if (s % 2 == 0) {
            a = automatic.step(s);
            o = off.step(s);
        } else {
            o = off.step(s);
            a = automatic.step(s);
        }
        autoRow.ms.push_back(a);
        offRow.ms.push_back(o);
        extraRow.ms.push_back(a - o);
    }
    const cullide::CullingDecision d = automatic.broadphase.getCullingDecision(cullide::CulledKind::GImpactPair);
    char note[200];
    std::snprintf(note, sizeof note, "GImpact pairs: %s (trial: culled %.2f ms, not culled %.2f ms; %zu abandoned)",
                  d.state.c_str(), d.culledMs, d.unculledMs, d.abandonedTrials);
    autoRow.note = note;
    extraRow.extraBound = autoRow.median() + 1.0;
    return {autoRow, offRow, extraRow};
}

}  // namespace

int main(int argc, char** argv) {
    int frames = 40;
    std::string json;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--frames" && i + 1 < argc) {
            frames = std::max(2, std::atoi(argv[++i]));
        } else if (a == "--json" && i + 1 < argc) {
            json = argv[++i];
        } else {
            std::fprintf(stderr, "usage: cullide-trial-bench [--frames N] [--json FILE]\n");
            return 2;
        }
    }
    std::vector<Row> rows;
    rows.push_back(cullerFrames("env1", 30, frames, true));
    rows.push_back(cullerFrames("env1", 30, frames, false));
    rows.push_back(cullerFrames("env3", 0, frames, true));
    rows.push_back(cullerFrames("env3", 0, frames, false));
    for (const bool anywhere : {false, true})
        for (const Row& r : swapSteps(3 * frames, anywhere)) rows.push_back(r);
    std::printf("%-66s %9s %9s %6s %8s %12s  %s\n", "", "median", "worst", "at", "bounded", "worst of 2..",
                "");
    for (const Row& r : rows)
        std::printf("%-66s %9.3f %9.3f %6zu %8s %12.3f  %s\n", r.what.c_str(), r.median(), r.worst(), r.worstAt(),
                    r.bounded() ? "yes" : "NO", r.worstAfterFirst(), r.note.c_str());
    if (!json.empty()) {
        std::ofstream out(json);
        out << "[\n";
        for (std::size_t i = 0; i < rows.size(); ++i)
            out << "  {\"what\": \"" << rows[i].what << "\", \"median_ms\": " << rows[i].median()
                << ", \"worst_ms\": " << rows[i].worst() << ", \"worst_at\": " << rows[i].worstAt()
                << ", \"worst_after_first_ms\": " << rows[i].worstAfterFirst()
                << ", \"bounded\": " << (rows[i].bounded() ? "true" : "false")
                << ", \"note\": \"" << rows[i].note << "\"}" << (i + 1 < rows.size() ? "," : "") << "\n";
        out << "]\n";
    }
    return 0;
}
