// cullide-bench-run: one (scene, engine) run per process, one JSON record out (appended to --out), so that each
// record's peak memory is its own. Driven by scripts/bench.sh; see docs/benchmarks.md.
//
//   cullide-bench-run --scene env1|env2|env3|env3-deform|stack|landscape|breakable --engine NAME
//                     [--objects N] [--tris N] [--frames N] [--warmup N] [--resolution N] [--group K]
//                     [--iterations N] [--min-prune F] [--threads N]
//                     [--truth FILE] [--tag TAG] [--out FILE] [--sample-every N]
//   cullide-bench-run --list-engines | --list-scenes   what this build can run
//   cullide-bench-run --probe          prints the GL renderer and device CULLIDE's GPU levels run on, and what a
//                                      dispatch, a fence and a read-back cost there (measureGlLatency), as JSON
//
// Frame scenes: the first --warmup frames run untimed, the next --frames are timed. With --engine exact the exact
// answer (the brute-force reference) of the timed frames is written to --truth; other engines read it from there
// and count missed and extra pairs. Frame scenes' records also hold each timed frame's ms, stage ms and minor page
// faults; every record lists the process's threads at the end (CPU time and allowed CPUs, grouped by name: the
// culler's workers are "cullide-worker", a GL driver's threads show up beside them) and the CPUs the main thread was
// allowed at the start. --threads N sets the CULLIDE engines' worker count (0: every core).
// Exit status: 0 ok, 2 bad arguments, 3 no GL, 4 scene or engine not built.
#include "BenchScene.h"
#include "Engine.h"
#include "PairSet.h"
#include "ProcessInfo.h"
#include "RunArgs.h"
#include "RunRecord.h"
#include "SteppingScene.h"
#ifdef CULLIDE_BENCH_BREAKABLE
#include "BreakableRun.h"
#endif

#include "cullide/Culler.h"
#include "cullide/GlLatency.h"
#include "cullide/Timer.h"
#include "cullide/scenes/Procedural.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace cullide::bench;

int usage(const std::string& why) {
    std::fprintf(stderr,
                 "cullide-bench-run: %s\nusage: cullide-bench-run --scene SCENE --engine ENGINE [--objects N] "
                 "[--tris N] [--frames N] [--warmup N] [--resolution N] [--group K] [--iterations N] [--min-prune F] [--threads N] "
                 "[--truth FILE] [--tag TAG] "
                 "[--out FILE] [--sample-every N] | --list-engines | --list-scenes | --probe\n",
                 why.c_str());
    return 2;
}

/// The process's threads grouped by (name, allowed CPUs): [{name, threads, cpu_ms, cpu_ms_max, cpus}], the most
/// CPU time first.
nlohmann::json threadsByName(const std::vector<ThreadUse>& threads) {
    std::vector<std::pair<std::pair<std::string, std::string>, std::vector<double>>> groups;
    for (const ThreadUse& t : threads) {
        const auto key = std::make_pair(t.name, t.cpus);
        auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == key; });
        if (it == groups.end()) it = groups.insert(groups.end(), {key, {}});
        it->second.push_back(t.cpuMs);
    }
    nlohmann::json out = nlohmann::json::array();
    for (const auto& [key, ms] : groups) {  // threads come most CPU first, so groups do too (by their busiest)
        double sum = 0.0;
        for (double v : ms) sum += v;
        out.push_back({{"name", key.first}, {"threads", ms.size()}, {"cpu_ms", sum}, {"cpu_ms_max", ms.front()},
                       {"cpus", key.second}});
    }
    return out;
}

int toInt(const std::string& s, const std::string& flag) {
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0') throw std::invalid_argument(flag + " needs an integer, got '" + s + "'");
    return static_cast<int>(v);
}

void emit(const RunArgs& args, const nlohmann::json& record) {
    const std::string line = record.dump();
    if (args.outPath.empty()) {
        std::cout << line << std::endl;
        return;
    }
    std::ofstream out(args.outPath, std::ios::app);
    if (!out) throw std::runtime_error("cannot append to " + args.outPath);
    out << line << '\n';
}

/// The GL device the GPU-level engines run on (GpuLevels::Always: Auto opens no context on a software renderer).
int probe() {
    cullide::Settings settings;
    settings.gpuLevels = cullide::GpuLevels::Always;
    std::unique_ptr<cullide::Culler> culler;
    try {
        culler = cullide::createGpuCuller(settings);
    } catch (const cullide::GlUnavailableError&) {
        std::cout << nlohmann::json{{"renderer", ""}, {"device", "none"}}.dump() << std::endl;
        return 0;
    }
    cullide::TriangleMesh a = cullide::scenes::makeBox(cullide::Vec3::Constant(0.5));
    cullide::TriangleMesh b = a;
    for (auto& p : b.vertices) p.x() += 0.5;
    std::vector<cullide::Object> objects(2);
    objects[0].mesh = &a;
    objects[1].mesh = &b;
    cullide::Result result;
    culler->run(objects, result);
    nlohmann::json j{{"renderer", result.stats.renderer}, {"device", result.stats.device}};
    try {  // what a round trip to that device costs (the floor under a frame of GPU levels)
        const cullide::GlLatency l = cullide::measureGlLatency(settings.device);
        j["latency"] = {{"dispatches", l.dispatches},
                        {"round_trips", l.roundTrips},
                        {"dispatch_issue_us", l.dispatchIssueUs},
                        {"fence_us", l.fenceUs},
                        {"read_back_us", l.readBackUs}};
        if (l.dispatchDeviceUs >= 0.0) j["latency"]["dispatch_device_us"] = l.dispatchDeviceUs;
    } catch (const std::exception& e) {
        j["latency"] = {{"error", e.what()}};
    }
    std::cout << j.dump() << std::endl;
    return 0;
}

void runFrames(const RunArgs& args, nlohmann::json& record) {
    SceneParams params;
    params.name = args.scene;
    params.objects = args.objects;
    params.trianglesPerObject = args.trianglesPerObject;
    BenchScene scene(params);
    record["objects"] = scene.objectCount();
    record["triangles"] = scene.triangleCount();
    record["stand_ins"] = scene.usedStandIns();
    if (scene.usedStandIns())
        std::fprintf(stderr, "cullide-bench-run: real meshes not found, using procedural stand-ins\n");

    EngineOptions options;
    options.resolution = args.resolution;
    options.groupSize = args.groupSize;
    options.maxIterations = args.maxIterations;
    options.minPruneFraction = args.minPruneFraction;
    options.threads = args.threads;
    auto engine = makeEngine(args.engine, options);
    const bool exactEngine = args.engine == "exact";

    Truth truth;
    if (!exactEngine && !args.truthPath.empty() && std::filesystem::exists(args.truthPath))
        truth = readTruth(args.truthPath);

    const cullide::Timer setupTimer;
    engine->setup(scene.frame(0));
    record["setup_ms"] = setupTimer.ms();

    FrameOutput out;
    RunRecord run;
    Truth written;
    double warmupMs = 0.0;
    for (int f = 0; f < args.warmup + args.frames; ++f) {
        const BenchFrame frame = scene.frame(f);
        if (f < args.warmup && exactEngine) continue;  // the oracle needs no warm-up
        const long faults = minorFaults();
        engine->run(frame, out);
        out.minorFaults = minorFaults() - faults;
        if (f < args.warmup) {
            warmupMs += out.totalMs;
            continue;
        }
        const auto it = truth.find(f);
        run.add(out, it != truth.end() ? &it->second : nullptr);
        if (exactEngine) written.emplace(f, out.pairs);
    }
    record["warmup_ms"] = warmupMs;
    run.write(record);
    run.writeFrames(record);
    record["process_threads"] = threadsByName(threadUse());  // while the engine's workers (and GL's threads) live
    if (exactEngine && !args.truthPath.empty()) writeTruth(args.truthPath, written);
    if (exactEngine) record["truth"] = "reference";
    const nlohmann::json described = engine->describe();
    for (const auto& [key, value] : described.items()) record[key] = value;
}

void runStepping(const RunArgs& args, nlohmann::json& record) {
    const cullide::Timer setupTimer;
    SteppingScene scene(args.scene, args.engine);
    record["setup_ms"] = setupTimer.ms();
    record["objects"] = scene.objectCount();
    record["triangles"] = scene.triangleCount();
    FrameOutput out;
    RunRecord run;
    for (int f = 0; f < args.warmup + args.frames; ++f) {
        const long faults = minorFaults();
        scene.step(out);
        out.minorFaults = minorFaults() - faults;
        if (f >= args.warmup) run.add(out, nullptr);
    }
    run.write(record);
    record["process_threads"] = threadsByName(threadUse());
    const nlohmann::json described = scene.describe();
    for (const auto& [key, value] : described.items()) record[key] = value;
}

}  // namespace

int main(int argc, char** argv) {
    RunArgs args;
    try {
        for (int i = 1; i < argc; ++i) {
            const std::string a = argv[i];
            auto value = [&]() -> std::string {
                if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
                return argv[++i];
            };
            if (a == "--scene") args.scene = value();
            else if (a == "--engine") args.engine = value();
            else if (a == "--objects") args.objects = toInt(value(), a);
            else if (a == "--tris") args.trianglesPerObject = toInt(value(), a);
            else if (a == "--frames") args.frames = toInt(value(), a);
            else if (a == "--warmup") args.warmup = toInt(value(), a);
            else if (a == "--resolution") args.resolution = toInt(value(), a);
            else if (a == "--group") args.groupSize = toInt(value(), a);
            else if (a == "--iterations") args.maxIterations = toInt(value(), a);
            else if (a == "--min-prune") args.minPruneFraction = std::stod(value());
            else if (a == "--threads") args.threads = toInt(value(), a);
            else if (a == "--sample-every") args.sampleEvery = toInt(value(), a);
            else if (a == "--truth") args.truthPath = value();
            else if (a == "--tag") args.tag = value();
            else if (a == "--out") args.outPath = value();
            else if (a == "--list-scenes") {
                std::printf("env1\nenv2\nenv3\nenv3-deform\nstack\nlandscape\n");
#ifdef CULLIDE_BENCH_BREAKABLE
                std::printf("breakable\n");
#endif
                return 0;
            } else if (a == "--list-engines") {
                for (const auto& n : engineNames()) std::printf("%s\n", n.c_str());
                return 0;
            } else if (a == "--probe") {
                return probe();
            } else {
                return usage("unknown argument " + a);
            }
        }
        if (args.frames < 1 || args.warmup < 0 || args.sampleEvery < 1 || args.threads < -1 || args.threads > 1024)
            return usage("--frames >= 1, --warmup >= 0, --sample-every >= 1, --threads 0 ... 1024");
    } catch (const std::invalid_argument& e) {
        return usage(e.what());
    } catch (const cullide::GlUnavailableError& e) {
        std::fprintf(stderr, "cullide-bench-run: %s\n", e.what());
        return 3;
    }

    nlohmann::json record;
    record["tag"] = args.tag;
    record["scene"] = args.scene;
    record["engine"] = args.engine;
    record["warmup"] = args.warmup;
    record["cpus_allowed_start"] = cpusAllowed();
    try {
        const cullide::Timer wall;
        if (args.scene == "stack" || args.scene == "landscape") {
            runStepping(args, record);
        } else if (args.scene == "breakable") {
#ifdef CULLIDE_BENCH_BREAKABLE
            runBreakable(args, record);
#else
            std::fprintf(stderr, "cullide-bench-run: the breakable scene is not built (no cullide_demo_scene target)\n");
            return 4;
#endif
        } else {
            runFrames(args, record);
        }
        record["wall_s"] = wall.ms() / 1000.0;
        record["peak_rss_kb"] = peakResidentKb();
        if (!record.contains("process_threads")) record["process_threads"] = threadsByName(threadUse());
        emit(args, record);
    } catch (const cullide::GlUnavailableError& e) {
        std::fprintf(stderr, "cullide-bench-run: %s\n", e.what());
        return 3;
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "cullide-bench-run: %s\n", e.what());
        return 4;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide-bench-run: %s\n", e.what());
        return 1;
    }
    return 0;
}
