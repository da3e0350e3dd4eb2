#include "BreakableRun.h"

#include "PairSet.h"
#include "ProcessInfo.h"
#include "RunRecord.h"

#include "cullide/Culler.h"
#include "cullide/Timer.h"
#include "cullide/demo/BreakableScene.h"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace cullide::bench {

namespace {

demo::CollisionPipeline pipelineOf(const std::string& engine) {
    if (engine == "cullide" || engine == "cullide-fast") return demo::CollisionPipeline::Cullide;
    if (engine == "bullet-dbvt") return demo::CollisionPipeline::BulletDbvt;
    if (engine == "bullet-sap") return demo::CollisionPipeline::BulletAxisSweep;
    throw std::invalid_argument("engine '" + engine + "' does not run the breakable scene (cullide, cullide-fast, "
                                "bullet-dbvt, bullet-sap)");
}

}  // namespace

void runBreakable(const RunArgs& args, nlohmann::json& record) {
    demo::BreakableOptions options;
    options.pipeline = pipelineOf(args.engine);
    // cullide-fast: interpenetrating GImpact pieces keep CULLIDE's near triangle pairs instead of Bullet's full
    // algorithm (CullideBroadphase::setDeepPenetrationFallback(false)): faster, fewer deep contacts.
    options.deepPenetrationFallback = args.engine != "cullide-fast";
    const Timer setupTimer;
    demo::BreakableScene scene(options);
    record["setup_ms"] = setupTimer.ms();
    record["stand_ins"] = scene.usedStandIns();
    auto reference = createReferenceCuller(Settings{});

    RunRecord run;
    FrameOutput out;
    Comparison objects;
    bool compared = false;
    std::size_t maxBodies = 0, maxTriangles = 0, samples = 0;
    std::vector<double> contactSteps;  // total ms of the steps with contact points (after the free fall)
    for (int f = 0; f < args.warmup + args.frames; ++f) {
        // Every n-th timed step: the exact object pairs of the bodies as that step's collision detection sees them
        // (the world before the step), against the pairs in the pipeline's pair cache after it.
        const bool sample = f >= args.warmup && (f - args.warmup) % args.sampleEvery == 0;
        PairSet exact;
        std::vector<std::string> names;
        if (sample) {
            const std::vector<TriangleMesh> meshes = scene.worldMeshes();
            names = scene.bodyNames();
            std::vector<Object> objectsIn(meshes.size());
            for (std::size_t i = 0; i < meshes.size(); ++i) objectsIn[i].mesh = &meshes[i];
            Result truth;
            reference->run(objectsIn, truth);
            for (const ObjectPair& p : truth.pairs)
                if (!p.triangles.empty()) exact.addObject(p.a, p.b);
            exact.finish();
        }
        const long faults = minorFaults();
        const demo::BreakableFrame& fr = scene.step();
        if (f < args.warmup) continue;
        out.clear();
        out.minorFaults = minorFaults() - faults;
        out.trianglePairsKnown = false;
        out.totalMs = fr.totalMs;
        const double known = fr.broadphaseMs + fr.narrowphaseMs + fr.solverMs + fr.fractureMs;
        if (options.pipeline == demo::CollisionPipeline::Cullide) {
            out.stages.push_back({"broadphase: cull", fr.cullide.cullMs});
            out.stages.push_back({"broadphase: rest", fr.broadphaseMs > fr.cullide.cullMs
                                                          ? fr.broadphaseMs - fr.cullide.cullMs : 0.0});
            out.candidates = fr.cullide.culler.candidateTrianglePairs;
            out.bytesUploaded = fr.cullide.culler.bytesUploaded;
            out.bytesReadBack = fr.cullide.culler.bytesReadBack;
            out.gpuDeviceBytes = fr.cullide.culler.gpuDeviceBytes;
        } else {
            out.stages.push_back({"broadphase", fr.broadphaseMs});
        }
        out.stages.push_back({"narrow phase", fr.narrowphaseMs});
        out.stages.push_back({"solver", fr.solverMs});
        out.stages.push_back({"fracture", fr.fractureMs});
        out.stages.push_back({"other", fr.totalMs > known ? fr.totalMs - known : 0.0});
        out.contacts = fr.contacts;
        if (fr.contacts > 0) contactSteps.push_back(fr.totalMs);
        maxBodies = std::max(maxBodies, fr.bodies);
        maxTriangles = std::max(maxTriangles, fr.triangles);
        if (sample) {
            std::map<std::string, std::uint32_t> index;
            for (std::size_t i = 0; i < names.size(); ++i) index[names[i]] = static_cast<std::uint32_t>(i);
            PairSet reported;
            for (const auto& [a, b] : scene.lastStepPairs()) {
                const auto ia = index.find(a), ib = index.find(b);
                if (ia != index.end() && ib != index.end()) reported.addObject(ia->second, ib->second);
            }
            reported.finish();
            objects += compareObjects(exact.objects(), reported.objects());
            compared = true;
            ++samples;
        }
        run.add(out, nullptr);
    }
    run.write(record);
    record["objects"] = maxBodies;
    record["triangles"] = maxTriangles;
    record["fractures"] = scene.fractures();
    record["contact_steps"] = contactSteps.size();
    if (!contactSteps.empty())
        record["ms_contact"] = {{"median", median(contactSteps)},
                                {"min", *std::min_element(contactSteps.begin(), contactSteps.end())},
                                {"max", *std::max_element(contactSteps.begin(), contactSteps.end())}};
    record["mode"] = options.pipeline == demo::CollisionPipeline::Cullide ? "reliable" : "bullet";
    if (compared) {
        // Object pairs only: the pipelines' pair caches (CULLIDE: pairs within its margin; Bullet: box overlaps).
        record["sampled_steps"] = samples;
        record["exact_object_pairs"] = objects.expected;
        record["missed_object_pairs"] = objects.missed;
        record["extra_object_pairs"] = objects.extra;
        record["reported_object_pairs"] = objects.reported;
    }
    if (const CullideBroadphase* bp = scene.cullideBroadphase()) {
        record["renderer"] = bp->getLastFrameStats().culler.renderer;
        record["device"] = bp->getLastFrameStats().culler.device;
        record["gpu_levels"] = "auto";
    }
}

}  // namespace cullide::bench
