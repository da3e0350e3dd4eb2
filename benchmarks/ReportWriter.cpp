#include "ReportWriter.h"

#include "ReportFormat.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

namespace cullide::bench {

namespace {

using nlohmann::json;

const std::vector<std::string> kSceneOrder = {"env1", "env2", "env3", "env3-deform", "stack", "landscape",
                                              "breakable"};
const std::vector<std::string> kEngineOrder = {"exact",          "cullide",        "cullide-fast",    "cullide-1t",
                                               "cullide-cpu",    "cullide-gpu",    "cullide-gpu-exact",
                                               "cullide-raster", "cullide-sampled",
                                               "bullet-dbvt",    "bullet-sap",     "fcl",             "fcl-aabb"};

double medianMs(const json& r) { return r.at("ms").at("median").get<double>(); }

std::string optCount(const json& r, const std::string& key) {
    const auto v = number(r, key);
    return v ? count(*v) : "–";
}

std::string engineLabel(const std::string& e, const json& r) {
    const int res = r.value("resolution", 256);
    if (e == "exact") return "exact (brute-force reference)";
    if (e == "cullide") return "**CULLIDE reliable** (default settings)";
    if (e == "cullide-1t") return "CULLIDE reliable, 1 thread";
    if (e == "cullide-fast") return "CULLIDE reliable, deep-penetration fallback off (Bullet adapter)";
    if (e == "cullide-cpu") return "CULLIDE reliable, GPU levels off (CPU path)";
    if (e == "cullide-gpu") return "CULLIDE reliable, GPU levels forced, " + std::to_string(res) + "²";
    if (e == "cullide-gpu-exact")
        return "CULLIDE reliable, GPU levels and exact-stage search on the device, " + std::to_string(res) + "²";
    if (e == "cullide-raster") return "CULLIDE reliable, GPU levels forced, raster back-end, " + std::to_string(res) + "²";
    if (e == "cullide-sampled") return "CULLIDE sampled, GPU levels forced, " + std::to_string(res) + "²";
    const bool stepping = r.value("mode", "") == "bullet";
    if (e == "bullet-dbvt") return stepping ? "Bullet btDbvtBroadphase (own dispatcher)" : "Bullet btDbvtBroadphase + GImpact";
    if (e == "bullet-sap") return stepping ? "Bullet btAxisSweep3 (own dispatcher)" : "Bullet btAxisSweep3 + GImpact";
    const std::string fclVersion = r.value("version", std::string());
    if (e == "fcl") return "FCL " + (fclVersion.empty() ? "" : fclVersion + " ") + "OBBRSS BVH";
    if (e == "fcl-aabb") return "FCL " + (fclVersion.empty() ? "" : fclVersion + " ") + "AABB BVH";
    return e;
}

std::string sceneLabel(const std::string& s, const json& r) {
    const std::string sizes = " — " + count(r.value("objects", 0.0)) + " objects, " +
                              count(r.value("triangles", 0.0)) + " triangles";
    if (s == "env1") return "env1: deforming open cylinders" + sizes;
    if (s == "env2") return "env2: deforming tori" + sizes;
    if (s == "env3") return "env3: bunny vs dragon, rigid" + sizes;
    if (s == "env3-deform") return "env3: deforming bunny vs dragon" + sizes;
    if (s == "stack") return "adapter regression: box stack, btDiscreteDynamicsWorld step" + sizes;
    if (s == "landscape") return "adapter regression: primitives and hulls on a landscape, step" + sizes;
    if (s == "breakable") return "breakable: bunny falls through the dragon, which breaks (step)" + sizes;
    return s;
}

std::string stages(const json& r) {
    std::string out;
    for (const auto& s : r.value("stages", json::array())) {
        if (!out.empty()) out += ", ";
        out += s.at(0).get<std::string>() + " " + ms(s.at(1).get<double>());
    }
    return out;
}

/// Least-squares slope and intercept of log(y) against log(x).
std::pair<double, double> logFit(const std::vector<std::pair<double, double>>& xy) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const double n = static_cast<double>(xy.size());
    for (const auto& [x, y] : xy) {
        const double lx = std::log(x), ly = std::log(y);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
    }
    const double d = n * sxx - sx * sx;
    if (xy.size() < 2 || d == 0.0) return {0.0, 0.0};
    const double a = (n * sxy - sx * sy) / d;
    return {a, (sy - a * sx) / n};
}

}  // namespace

ReportWriter::ReportWriter(std::vector<json> results, std::string docPath, std::string plotDir, std::string dataDir)
    : m_docPath(std::move(docPath)), m_plotDir(std::move(plotDir)), m_dataDir(std::move(dataDir)) {
    for (auto& r : results) {
        Class c;
        c.machine = r.at("machine");
        c.name = c.machine.value("class", "cpu");
        for (auto& rec : r.at("records")) c.records.push_back(rec);
        m_classes.push_back(std::move(c));
    }
    std::sort(m_classes.begin(), m_classes.end(), [](const Class& a, const Class& b) { return a.name < b.name; });
}

const json* ReportWriter::find(const Class& c, const std::string& tag, const std::string& scene,
                               const std::string& engine) const {
    for (const auto& r : c.records)
        if (r.value("tag", "") == tag && r.value("scene", "") == scene && r.value("engine", "") == engine &&
            r.contains("ms"))
            return &r;
    return nullptr;
}

std::vector<std::string> ReportWriter::scenes(const Class& c, const std::string& tag) const {
    std::vector<std::string> out;
    for (const auto& s : kSceneOrder)
        for (const auto& r : c.records)
            if (r.value("tag", "") == tag && r.value("scene", "") == s) {
                out.push_back(s);
                break;
            }
    return out;
}

const json* ReportWriter::bestPeer(const Class& c, const std::string& scene, bool gimpactOnly) const {
    const json* best = nullptr;
    for (const auto& e : peerEngines()) {
        if (gimpactOnly && e.rfind("bullet", 0) != 0) continue;
        const json* r = find(c, "side", scene, e);
        if (r != nullptr && (best == nullptr || medianMs(*r) < medianMs(*best))) best = r;
    }
    return best;
}

std::string ReportWriter::image(const std::string& file) const {
    namespace fs = std::filesystem;
    const fs::path doc = fs::absolute(m_docPath).parent_path();
    const fs::path png = fs::absolute(fs::path(m_plotDir) / file);
    return png.lexically_relative(doc).generic_string();
}

void ReportWriter::writeFile(const std::string& name, const std::string& text) const {
    const std::string path = (std::filesystem::path(m_dataDir) / name).string();
    std::ofstream out(path);
    out << text;
    if (!out) throw std::runtime_error("cannot write " + path);
}

void ReportWriter::write() {
    m_md << "# Benchmarks\n\n"
            "<!-- Generated by scripts/bench.sh (cullide-bench-report) from docs/bench/results-*.json. Do not edit: "
            "rerun the script. -->\n\n"
            "`scripts/bench.sh` builds `cullide-bench-run` and runs every (scene, engine) pair as its own process "
            "on the same frames, then writes this page, its plots (`docs/bench/*.png`, gnuplot, headless) and the "
            "raw records (`out/bench/results.json`, kept per machine class in `docs/bench/results-<class>.json`). "
            "`scripts/bench.sh --quick` is a ~3-minute smoke run into `out/bench/` only.\n\n"
            "**What every engine computes.** All intersecting triangle pairs of the frame's world-space meshes; "
            "deforming meshes change every frame. CULLIDE: `createGpuCuller(settings)->run(objects, result)`, "
            "its pairs carry the exact triangle pairs. Bullet: a `btCollisionWorld` with one `btGImpactMeshShape` "
            "per object (collision margin 0), deforming vertex arrays rewritten in place and refitted with "
            "`postUpdate()` + `updateBound()`, rigid objects moved by their transform; `btDbvtBroadphase` or "
            "`btAxisSweep3`, `btCollisionDispatcher` with GImpact registered; timed as `updateAabbs`, "
            "`computeOverlappingPairs`, `dispatchAllCollisionPairs` (what `performDiscreteCollisionDetection` "
            "does). GImpact produces contact points, not triangle-pair lists: its triangle pairs are the "
            "(object, triangle) ids of the contact points it generated (`gContactAddedCallback`), its object "
            "pairs those with contact points. FCL: one `BVHModel` per object (OBBRSS, FCL's usual mesh volume, "
            "and AABB, cheaper to refit), deforming ones refitted with `beginUpdateModel` / `updateSubModel` / "
            "`endUpdateModel`, a `DynamicAABBTreeCollisionManager` and `fcl::collide` per candidate pair with an "
            "unbounded contact count (`Contact::b1/b2` are the triangles). Rigid objects (the bunny of env3) are "
            "a fixed mesh plus a transform for Bullet, FCL and CULLIDE (`Object::transform`), as an application "
            "would model them; CULLIDE takes world-space triangles for the others, and static and rigid objects "
            "carry `Object::staticKey`.\n\n"
            "**Timing.** Milliseconds per frame (wall clock, median / min / max over the timed frames, after one "
            "untimed warm-up frame that includes shader compilation); the stage split is the median of each stage. "
            "CULLIDE's exact stage uses every core (`Settings::threads = 0`); Bullet and FCL run on one thread, "
            "so \"CULLIDE reliable, 1 thread\" is listed too. Ratios are to the fastest peer (Bullet or FCL) in "
            "the same run.\n\n"
            "**Error.** Against the exact answer of the same frames: the brute-force reference culler "
            "(`createReferenceCuller`: every triangle pair of box-overlapping objects, exact predicates). "
            "*Missed* = exact pairs not reported, *extra* = reported pairs that do not intersect. The "
            "false-positive ratio is CULLIDE's cost of culling: candidate triangle pairs handed to the exact test "
            "divided by the exact pairs. Reliable mode must miss nothing.\n\n"
            "**GPU levels and `Auto`.** With `GpuLevels::Auto` (the default) the culler times both paths on the "
            "scene's first frames (CPU path, GPU levels, CPU path, GPU levels; the last two compared) and runs the "
            "faster; section 5 of each machine lists the decision and both timings. Where the CPU path wins, "
            "resolution has no effect on the default path, so the resolution sweep forces the GPU levels "
            "(`GpuLevels::Always`) and shows the default path as a reference line. The trial frames are among the "
            "timed frames: they show in the max column, not in the median.\n\n"
            "**Memory.** Peak resident memory (VmHWM) of the process that ran the (scene, engine) pair, scene "
            "generation included. GL device bytes: `Stats::gpuDeviceBytes`, what the culler holds on its GL device "
            "(buffer capacities, which only grow, plus the four view images, allocated even when no GPU level runs) "
            "— the driver's own allocations are not counted; bytes uploaded and read back are per frame.\n\n";
    machines();
    targets();
    for (const auto& c : m_classes) {
        m_md << "## Results: " << classTitle(c.name) << "\n\n";
        sideBySide(c);
        sweep(c);
        scaling(c);
        memory(c);
        gpuLevels(c);
        threads(c);
    }
    gpuComparison();
    m_md << "## Reproduce\n\n```sh\nscripts/bench.sh            # full run, writes this page\nscripts/bench.sh --quick    "
            "# smoke run into out/bench/\nbuild-bench/benchmarks/cullide-bench-run --scene env3-deform --engine "
            "cullide --frames 4   # one record\n```\n`cullide-bench-run --help` lists the flags; "
            "`scripts/bench_core.sh` gives the culler's own per-level figures (docs/performance.md).\n";
    std::ofstream out(m_docPath);
    out << m_md.str();
    if (!out) throw std::runtime_error("cannot write " + m_docPath);
}

void ReportWriter::machines() {
    m_md << "## Machines\n\n| class | date (UTC) | CPU | cores | memory | GL renderer (CULLIDE's device) | Mesa | "
            "NVIDIA | load before → after | run time | commit |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : m_classes) {
        const json& m = c.machine;
        const json probe = m.value("probe", json::object());
        m_md << "| " << c.name << (m.value("quick", false) ? " (quick run)" : "") << " | " << m.value("date", "")
             << " | " << m.value("cpu", "") << " | " << m.value("cores", 0) << " | "
             << fixed(m.value("memory_gib", 0.0), 1) << " GiB | " << cell(probe.value("renderer", "none")) << " ("
             << cell(probe.value("device", "")) << ") | " << m.value("mesa_package", "") << " | "
             << (m.value("nvidia", "").empty() ? "–" : m.value("nvidia", "")) << " | " << m.value("load_before", "")
             << " → " << m.value("load_after", "") << " | " << count(m.value("runtime_s", 0.0) / 60.0) << " min | "
             << m.value("commit", "") << " |\n";
    }
    m_md << "\nThe load average is the machine's (1, 5, 15 min): other builds shared this machine during the run "
            "when it is well above 0; rerun on a quiet machine for clean figures.\n\n";
    // The floor under a frame of GPU levels on each machine's device (measureGlLatency, medians).
    std::string latencies;
    for (const auto& c : m_classes) {
        const json probe = c.machine.value("probe", json::object());
        const json l = probe.value("latency", json::object());
        if (!l.contains("fence_us")) continue;
        // The cpu class is a software renderer's (scripts/bench.sh), which runs a dispatch as it is issued: its
        // timer spans nothing.
        const std::string onDevice = l.contains("dispatch_device_us") && c.name != "cpu"
                                         ? fixed(l.value("dispatch_device_us", 0.0), 2) + " µs on the device, "
                                         : "";
        latencies += "- " + c.name + ": a dependent dispatch " + onDevice +
                     fixed(l.value("dispatch_issue_us", 0.0), 2) + " µs to issue; a fence after one " +
                     fixed(l.value("fence_us", 0.0), 2) + " µs; a blocking read-back of 4 bytes " +
                     fixed(l.value("read_back_us", 0.0), 2) + " µs.\n";
    }
    if (!latencies.empty())
        m_md << "**GL round trips** (`cullide-bench-run --probe`, `measureGlLatency`: medians; on a software renderer "
                "a dispatch runs as it is issued, so its cost is the issue time):\n\n"
             << latencies << "\n";
}

void ReportWriter::targets() {
    m_md << "## Targets\n\nRatios in one run: CULLIDE reliable (default settings) against the fastest peer. CPU "
            "only: at most 0.5× Bullet's GImpact pipeline per frame on env2, env3 (deforming) and breakable, at "
            "most 1× on env1. Hardware GPU: at most 0.1× the best CPU peer on every scene.\n\n";
    for (const auto& c : m_classes) {
        m_md << "### " << classTitle(c.name) << "\n\n| scene | target | CULLIDE ms | peer ms | ratio | met | "
                                                "dominating stage of CULLIDE |\n|---|---|---|---|---|---|---|\n";
        std::vector<std::pair<std::string, double>> goals;
        if (c.name == "gpu") {
            for (const auto& s : scenes(c, "side")) goals.emplace_back(s, 0.1);
        } else {
            goals = {{"env1", 1.0}, {"env2", 0.5}, {"env3-deform", 0.5}, {"breakable", 0.5}};
        }
        for (const auto& [scene, goal] : goals) {
            const json* mine = find(c, "side", scene, "cullide");
            const json* peer = bestPeer(c, scene, c.name != "gpu");
            if (mine == nullptr || peer == nullptr) {
                m_md << "| " << scene << " | ≤ " << fixed(goal, 1) << "× | – | – | – | not measured | "
                     << (scene == "breakable" ? "the breakable scene was not built in this run" : "no record")
                     << " |\n";
                continue;
            }
            const double r = medianMs(*mine) / medianMs(*peer);
            std::string why;
            const json& st = mine->value("stages", json::array());
            double top = -1, sum = 0;
            std::string topName;
            for (const auto& s : st) {
                const double v = s.at(1).get<double>();
                sum += v;
                if (v > top) {
                    top = v;
                    topName = s.at(0).get<std::string>();
                }
            }
            if (!topName.empty() && sum > 0) {
                why = topName + ": " + ms(top) + " of " + ms(medianMs(*mine)) + " ms (" +
                      fixed(100.0 * top / sum, 0) + "%)";
                const auto cand = number(*mine, "candidate_triangle_pairs");
                const auto exact = number(*mine, "exact_triangle_pairs");
                const double frames = mine->value("frames", 1.0);
                if (topName == "exact" && cand && exact && *exact > 0) {
                    why += "; " + count(*cand / frames) + " candidate triangle pairs per frame = " +
                           fixed(*cand / *exact, 1) + "× the exact pairs, " +
                           fixed(1000.0 * top / (*cand / frames), 2) + " µs per candidate";
                }
            }
            if (mine->contains("ms_contact") && peer->contains("ms_contact")) {
                const double a = mine->at("ms_contact").at("median").get<double>();
                const double b = peer->at("ms_contact").at("median").get<double>();
                why += "; steps with contact points only: " + ms(a) + " vs " + ms(b) + " ms = " + ratio(a / b);
            }
            m_md << "| " << scene << " | ≤ " << fixed(goal, 1) << "× | " << ms(medianMs(*mine)) << " | "
                 << ms(medianMs(*peer)) << " (" << peer->value("engine", "") << ") | " << ratio(r) << " | "
                 << (r <= goal ? "**met**" : "**not met**") << " | " << why << " |\n";
        }
        m_md << "\n";
    }
    bool anyGpu = false;
    for (const auto& c : m_classes) anyGpu = anyGpu || c.name == "gpu";
    if (!anyGpu)
        m_md << "The GPU targets are not measured yet: no NVIDIA machine has run `scripts/bench.sh` "
                "(its results would go to `docs/bench/results-gpu.json` and appear beside these).\n\n";
}

void ReportWriter::sideBySide(const Class& c) {
    m_md << "### 1. Side by side (" << c.name << ")\n\n![ms per frame](" << image("side-" + c.name + ".png")
         << ")\n\n";
    for (const auto& scene : scenes(c, "side")) {
        const json* any = nullptr;
        for (const auto& r : c.records)
            if (r.value("tag", "") == "side" && r.value("scene", "") == scene) any = &r;
        const json* peer = bestPeer(c, scene, false);
        m_md << "**" << sceneLabel(scene, *any) << "** (" << any->value("frames", 0) << " timed "
             << (scene == "stack" || scene == "landscape" || scene == "breakable" ? "steps" : "frames");
        if (any->value("stand_ins", false)) m_md << ", procedural stand-in meshes";
        m_md << ")\n\n| engine | median ms | min | max | × best peer | stages (median ms) | object pairs "
                "missed / extra | triangle pairs missed / extra | exact pairs (obj / tri) |\n"
                "|---|---|---|---|---|---|---|---|---|\n";
        for (const auto& e : kEngineOrder) {
            const json* r = find(c, "side", scene, e);
            if (r == nullptr) continue;
            const double med = medianMs(*r);
            m_md << "| " << engineLabel(e, *r) << " | " << ms(med) << " | " << ms(r->at("ms").at("min").get<double>())
                 << " | " << ms(r->at("ms").at("max").get<double>()) << " | "
                 << (peer != nullptr ? ratio(med / medianMs(*peer)) : "–") << " | " << stages(*r) << " | ";
            if (r->contains("missed_object_pairs"))
                m_md << optCount(*r, "missed_object_pairs") << " / " << optCount(*r, "extra_object_pairs");
            else
                m_md << "–";
            m_md << " | ";
            if (r->contains("missed_triangle_pairs"))
                m_md << optCount(*r, "missed_triangle_pairs") << " / " << optCount(*r, "extra_triangle_pairs");
            else
                m_md << "–";
            m_md << " | ";
            if (r->contains("exact_object_pairs"))
                m_md << optCount(*r, "exact_object_pairs") << " / " << optCount(*r, "exact_triangle_pairs");
            else if (e == "exact")
                m_md << optCount(*r, "reported_object_pairs") << " / " << optCount(*r, "reported_triangle_pairs");
            else
                m_md << "–";
            m_md << " |\n";
        }
        m_md << "\n";
        if (scene == "breakable") {
            for (const auto& e : kEngineOrder) {
                const json* r = find(c, "side", scene, e);
                if (r == nullptr || !r->contains("ms_contact")) continue;
                m_md << "- " << e << ": " << r->value("contact_steps", 0) << " steps with contact points, median "
                     << ms(r->at("ms_contact").at("median").get<double>()) << " ms (max "
                     << ms(r->at("ms_contact").at("max").get<double>()) << "); " << r->value("fractures", 0)
                     << " fractures; exact object pairs checked on " << r->value("sampled_steps", 0) << " steps\n";
            }
            m_md << "\n";
        }
    }
    m_md << "GImpact's *extra* triangle pairs are pairs that do not intersect but produced contact points: "
            "Bullet keeps points up to the contact breaking threshold (0.02 by default) apart, and its clipping "
            "routine also reports near-touching pairs. FCL's triangle test is floating point (not exact); a miss "
            "or extra pair of FCL would show here. "
            "Pair counts are summed over the timed frames. The stepping scenes' stages are those of one "
            "`stepSimulation`. Stack and landscape have no exact oracle here (the adapter's mirror tests check their "
            "contacts). Breakable: the pipelines share the seed and so the start, but their trajectories diverge "
            "after contacts; on every n-th step the object pairs in the pipeline's pair cache are compared with "
            "the exact object pairs of the bodies that step's collision detection saw (reference culler over "
            "`BreakableScene::worldMeshes()`); *extra* pairs are expected there (CULLIDE keeps pairs within its "
            "margin, Bullet box overlaps). Its median covers the whole run, the free fall included; the median of "
            "the steps with contact points only is listed below the table where recorded.\n\n";
    plotSide(c);
}

void ReportWriter::plotSide(const Class& c) {
    std::ostringstream dat;
    std::vector<std::string> cols;
    const std::vector<std::string> engines = {"cullide", "cullide-1t", "cullide-gpu", "bullet-dbvt", "bullet-sap",
                                              "fcl", "fcl-aabb"};
    dat << "scene";
    for (const auto& e : engines) dat << ' ' << e;
    dat << '\n';
    for (const auto& scene : scenes(c, "side")) {
        dat << scene;
        for (const auto& e : engines) {
            const json* r = find(c, "side", scene, e);
            dat << ' ' << (r != nullptr ? fixed(medianMs(*r), 4) : "NaN");
        }
        dat << '\n';
    }
    const std::string dataFile = "side-" + c.name + ".dat";
    writeFile(dataFile, dat.str());
    std::ostringstream gp;
    gp << "set terminal pngcairo size 1000,520 noenhanced font ',10'\nset output '"
       << (std::filesystem::path(m_plotDir) / ("side-" + c.name + ".png")).string() << "'\n"
       << "set title 'ms per frame / step (median), " << classTitle(c.name) << "'\nset style data histogram\n"
       << "set style histogram clustered gap 1\nset style fill solid 0.8 border -1\nset logscale y\n"
       << "set ylabel 'ms (log)'\nset key outside right\nset grid ytics\n"
       << "plot for [i=2:" << engines.size() + 1 << "] '"
       << (std::filesystem::path(m_dataDir) / dataFile).string() << "' using i:xtic(1) title columnheader(i)\n";
    writeFile("side-" + c.name + ".gp", gp.str());
}

void ReportWriter::sweep(const Class& c) {
    const auto sweepScenes = scenes(c, "sweep");
    m_md << "### 2. Speed against error (" << c.name << ")\n\n";
    if (sweepScenes.empty()) {
        m_md << "No resolution sweep in this run.\n\n";
        return;
    }
    m_md << "GPU levels forced (`GpuLevels::Always`), groups of 32, both modes; the default path (GPU levels "
            "skipped on this device when it is software) is the reference. Error summed over the timed frames.\n\n"
         << "![time against resolution](" << image("sweep-time-" + c.name + ".png") << ")\n![time against error]("
         << image("tradeoff-" + c.name + ".png") << ")\n\n";
    for (const auto& scene : sweepScenes) {
        m_md << "**" << scene << "**";
        if (const json* d = find(c, "side", scene, "cullide"))
            m_md << " — default path (reliable, Auto): " << ms(medianMs(*d)) << " ms, missed "
                 << optCount(*d, "missed_triangle_pairs") << " triangle pairs, false-positive ratio "
                 << (number(*d, "false_positive_ratio") ? fixed(*number(*d, "false_positive_ratio"), 2) : "–");
        m_md << "\n\n| mode | resolution | median ms | gpu levels ms | missed triangle pairs | missed % | missed "
                "object pairs | exact (obj / tri) | candidates | false-positive ratio |\n"
                "|---|---|---|---|---|---|---|---|---|---|\n";
        for (const std::string mode : {"cullide-gpu", "cullide-sampled"}) {
            std::vector<const json*> rows;
            for (const auto& r : c.records)
                if (r.value("tag", "") == "sweep" && r.value("scene", "") == scene && r.value("engine", "") == mode &&
                    r.contains("ms"))
                    rows.push_back(&r);
            std::sort(rows.begin(), rows.end(),
                      [](const json* a, const json* b) { return a->value("resolution", 0) < b->value("resolution", 0); });
            for (const json* r : rows) {
                double levels = 0;
                for (const auto& s : r->value("stages", json::array()))
                    if (s.at(0) == "gpu levels") levels = s.at(1).get<double>();
                const int res = r->value("resolution", 0);
                m_md << "| " << (mode == "cullide-gpu" ? "reliable" : "sampled") << " | " << res << "² | "
                     << ms(medianMs(*r)) << " | " << ms(levels) << " | " << optCount(*r, "missed_triangle_pairs")
                     << " | "
                     << (r->value("exact_triangle_pairs", 0.0) > 0
                             ? fixed(100.0 * r->value("missed_triangle_pairs", 0.0) /
                                         r->value("exact_triangle_pairs", 1.0), 1)
                             : "–")
                     << " | " << optCount(*r, "missed_object_pairs") << " | " << optCount(*r, "exact_object_pairs")
                     << " / " << optCount(*r, "exact_triangle_pairs") << " | "
                     << optCount(*r, "candidate_triangle_pairs") << " | "
                     << (number(*r, "false_positive_ratio") ? fixed(*number(*r, "false_positive_ratio"), 2) : "–")
                     << " |\n";
            }
        }
        m_md << "\n";
    }
    plotSweep(c);
}

void ReportWriter::plotSweep(const Class& c) {
    namespace fs = std::filesystem;
    std::ostringstream time, trade;
    std::string timePlots, reliablePlots, sampledPlots;
    int style = 1;
    for (const auto& scene : scenes(c, "sweep")) {
        for (const std::string mode : {"cullide-gpu", "cullide-sampled"}) {
            std::vector<const json*> rows;
            for (const auto& r : c.records)
                if (r.value("tag", "") == "sweep" && r.value("scene", "") == scene && r.value("engine", "") == mode &&
                    r.contains("ms"))
                    rows.push_back(&r);
            if (rows.empty()) continue;
            std::sort(rows.begin(), rows.end(),
                      [](const json* a, const json* b) { return a->value("resolution", 0) < b->value("resolution", 0); });
            std::ostringstream dat;
            dat << "# resolution ms false_positive_ratio missed_percent\n";
            for (const json* r : rows) {
                const double exact = r->value("exact_triangle_pairs", 0.0);
                const double missed = r->value("missed_triangle_pairs", 0.0);
                dat << r->value("resolution", 0) << ' ' << fixed(medianMs(*r), 4) << ' '
                    << (number(*r, "false_positive_ratio") ? fixed(*number(*r, "false_positive_ratio"), 4) : "NaN")
                    << ' ' << (exact > 0 ? fixed(100.0 * missed / exact, 4) : "NaN") << '\n';
            }
            const std::string file = "sweep-" + c.name + "-" + scene + "-" + mode + ".dat";
            writeFile(file, dat.str());
            const std::string path = (fs::path(m_dataDir) / file).string();
            const std::string title = scene + (mode == "cullide-gpu" ? " reliable" : " sampled");
            timePlots += (timePlots.empty() ? "" : ", ") + ("'" + path + "' using 1:2 with linespoints lw 2 lc " +
                                                           std::to_string(style) + " title '" + title + "'");
            if (mode == "cullide-gpu")
                reliablePlots += (reliablePlots.empty() ? "" : ", ") +
                                 ("'" + path + "' using 2:3 with linespoints lw 2 lc " + std::to_string(style) +
                                  " title '" + scene + "', '' using 2:3:(sprintf('%d', $1)) with labels offset 0,1 "
                                  "notitle");
            else
                sampledPlots += (sampledPlots.empty() ? "" : ", ") +
                                ("'" + path + "' using 2:4 with linespoints lw 2 lc " + std::to_string(style) +
                                 " title '" + scene + "', '' using 2:4:(sprintf('%d', $1)) with labels offset 0,1 "
                                 "notitle");
            ++style;
        }
        if (const json* d = find(c, "side", scene, "cullide"))
            timePlots += ", " + fixed(medianMs(*d), 4) + " with lines dt 2 lw 2 lc " + std::to_string(style++) +
                         " title '" + scene + " default path (Auto)'";
    }
    time << "set terminal pngcairo size 900,560 noenhanced font ',10'\nset output '"
         << (fs::path(m_plotDir) / ("sweep-time-" + c.name + ".png")).string() << "'\n"
         << "set title 'CULLIDE ms per frame against resolution (GPU levels forced), " << classTitle(c.name)
         << "'\nset logscale xy\nset xlabel 'resolution (pixels per side)'\nset ylabel 'ms per frame'\n"
         << "set grid\nset key top left\nplot " << timePlots << "\n";
    writeFile("sweep-time-" + c.name + ".gp", time.str());
    trade << "set terminal pngcairo size 1100,480 noenhanced font ',10'\nset output '"
          << (fs::path(m_plotDir) / ("tradeoff-" + c.name + ".png")).string() << "'\n"
          << "set multiplot layout 1,2 title 'time against error (labels: resolution), " << classTitle(c.name)
          << "'\nset logscale x\nset grid\nset xlabel 'ms per frame'\n"
          << "set title 'reliable: never misses; cost = candidates / exact pairs'\nset ylabel 'false-positive ratio'\n"
          << "plot " << (reliablePlots.empty() ? "NaN notitle" : reliablePlots) << "\n"
          << "set title 'sampled: missed share of the exact triangle pairs'\nset ylabel 'missed (%)'\n"
          << "set key bottom left\n"
          << "set yrange [0:105]\nplot " << (sampledPlots.empty() ? "NaN notitle" : sampledPlots)
          << "\nunset multiplot\n";
    writeFile("tradeoff-" + c.name + ".gp", trade.str());
}

void ReportWriter::scaling(const Class& c) {
    m_md << "### 3. Scaling (" << c.name << ")\n\nMedian ms per frame; slope = least-squares fit of log(ms) "
            "against log(x) (1 = linear).\n\n";
    const std::vector<std::pair<std::string, std::string>> sweeps = {
        {"scale-objects", "objects (env1, 200 triangles each)"},
        {"scale-triangles", "triangles per object (env2, 6 deforming tori)"}};
    for (const auto& [tag, label] : sweeps) {
        std::map<std::string, std::vector<std::pair<double, double>>> series;
        std::set<double> xs;
        for (const auto& r : c.records) {
            if (r.value("tag", "") != tag || !r.contains("ms")) continue;
            const double objects = r.value("objects", 1.0);
            const double x = tag == "scale-objects" ? objects : std::round(r.value("triangles", 0.0) / objects);
            series[r.value("engine", "")].emplace_back(x, medianMs(r));
            xs.insert(x);
        }
        if (series.empty()) continue;
        m_md << "**" << label << "**\n\n![scaling](" << image(tag + "-" + c.name + ".png") << ")\n\n| engine | slope |";
        for (double x : xs) m_md << ' ' << count(x) << " |";
        m_md << "\n|---|---|";
        for (std::size_t i = 0; i < xs.size(); ++i) m_md << "---|";
        m_md << "\n";
        std::ostringstream gpPlots;
        int style = 1;
        for (const auto& e : kEngineOrder) {
            auto it = series.find(e);
            if (it == series.end()) continue;
            auto& pts = it->second;
            std::sort(pts.begin(), pts.end());
            const auto [slope, intercept] = logFit(pts);
            m_md << "| " << engineLabel(e, json::object()) << " | " << fixed(slope, 2) << " |";
            for (double x : xs) {
                const auto p = std::find_if(pts.begin(), pts.end(), [x](const auto& q) { return q.first == x; });
                m_md << ' ' << (p != pts.end() ? ms(p->second) : "–") << " |";
            }
            m_md << "\n";
            std::ostringstream dat;
            for (const auto& [x, y] : pts) dat << x << ' ' << fixed(y, 4) << '\n';
            const std::string file = tag + "-" + c.name + "-" + e + ".dat";
            writeFile(file, dat.str());
            const std::string path = (std::filesystem::path(m_dataDir) / file).string();
            if (style > 1) gpPlots << ", ";
            gpPlots << "'" << path << "' using 1:2 with points pt 7 ps 1.2 lc " << style << " title '" << e
                    << " (slope " << fixed(slope, 2) << ")', exp(" << fixed(intercept, 6) << ")*x**"
                    << fixed(slope, 6) << " with lines lc " << style << " notitle";
            ++style;
        }
        m_md << "\n";
        std::ostringstream gp;
        gp << "set terminal pngcairo size 900,560 noenhanced font ',10'\nset output '"
           << (std::filesystem::path(m_plotDir) / (tag + "-" + c.name + ".png")).string() << "'\n"
           << "set title 'ms per frame against " << label << ", " << classTitle(c.name) << "'\n"
           << "set logscale xy\nset grid\nset key top left\nset xlabel '" << label << "'\nset ylabel 'ms per frame'\n"
           << "plot " << gpPlots.str() << "\n";
        writeFile(tag + "-" + c.name + ".gp", gp.str());
    }
    // Resolution: from the sweep (GPU levels, reliable).
    for (const auto& scene : scenes(c, "sweep")) {
        std::vector<std::pair<double, double>> pts;
        for (const auto& r : c.records)
            if (r.value("tag", "") == "sweep" && r.value("scene", "") == scene &&
                r.value("engine", "") == "cullide-gpu" && r.contains("ms"))
                pts.emplace_back(r.value("resolution", 0.0), medianMs(r));
        if (pts.size() < 2) continue;
        std::sort(pts.begin(), pts.end());
        const auto fit = logFit(pts);
        m_md << "Resolution (" << scene << ", reliable, GPU levels forced, " << count(pts.front().first) << "² – "
             << count(pts.back().first) << "², plot in part 2): slope " << fixed(fit.first, 2)
             << " against the side length (2 = proportional to the pixel count).\n\n";
    }
}

void ReportWriter::memory(const Class& c) {
    m_md << "### 4. Memory (" << c.name << ")\n\n| scene | engine | peak resident MiB | GL device bytes (max) | bytes "
            "uploaded per frame (max) | bytes read back per frame (max) | set-up ms |\n|---|---|---|---|---|---|---|\n";
    for (const auto& scene : scenes(c, "side"))
        for (const auto& e : kEngineOrder) {
            const json* r = find(c, "side", scene, e);
            if (r == nullptr) continue;
            const double device = r->value("gpu_device_bytes_max", 0.0);
            m_md << "| " << scene << " | " << e << " | " << fixed(r->value("peak_rss_kb", 0.0) / 1024.0, 1) << " | "
                 << (device > 0 ? count(device) : std::string("–")) << " | " << count(r->value("bytes_uploaded_max", 0.0)) << " | " << count(r->value("bytes_read_back_max", 0.0))
                 << " | " << (number(*r, "setup_ms") ? ms(*number(*r, "setup_ms")) : "–") << " |\n";
        }
    m_md << "\nPeak resident memory includes the scene generator's meshes (every process holds them) and, for "
            "CULLIDE, the GL driver (llvmpipe allocates its images in host memory).\n\n";
}

void ReportWriter::gpuLevels(const Class& c) {
    m_md << "### 5. GPU levels and the Auto decision (" << c.name << ")\n\n"
            "`Auto`: the decision after the last frame and the timed trial frames behind it (whole-frame ms; on a "
            "software renderer `Auto` does not trial and runs the CPU path). GPU levels forced: the levels' wall time (CPU side included: records, uploads, waiting for the flags), "
            "their GPU time from timer queries (– where the driver's timer is absent or implausible) and the "
            "draws and dispatches and the read-backs that waited for the device per frame (medians, and in brackets the "
            "largest of any frame: the first timed frame, where the buffers grow and a cluster may run again; a frame "
            "waits once however many clusters it has); per level, the last frame's items per iteration and its CPU / "
            "GPU ms (\"ahead\": a level run ahead, its device time read with the next level's; a deferred level's "
            "CPU ms include the frame's wait when it is the last; a deferred triangle level's GPU ms include the "
            "device exact stage's, also shown apart), and of the CPU ms the set-up (item data and records built and "
            "sent; of it, the GL calls "
            "that send them, and the records sent) and the time blocked in read-backs (waiting for the device); the "
            "rest is issuing commands.\n\n| scene | Auto decision | "
            "trial: CPU path ms | trial: GPU levels ms | engine | levels "
            "wall ms | levels GPU ms | draws / read-backs (max) | per level (last frame): items per iteration, CPU / GPU ms |\n"
            "|---|---|---|---|---|---|---|---|---|\n";
    std::ostringstream rows;
    for (const auto& scene : scenes(c, "side")) {
        const json* a = find(c, "side", scene, "cullide");
        const bool decided = a != nullptr && !a->value("auto_decision", std::string()).empty();
        const std::string decision = decided ? a->value("auto_decision", std::string()) : "not trialled";
        const std::string cpuTrial = decided ? ms(a->value("auto_cpu_ms", 0.0)) : "–";
        const std::string gpuTrial = decided ? ms(a->value("auto_gpu_ms", 0.0)) : "–";
        for (const std::string e : {"cullide-gpu", "cullide-gpu-exact", "cullide-raster"}) {
            const json* r = find(c, "side", scene, e);
            if (r == nullptr) continue;
            double wall = 0.0;
            for (const auto& stage : r->value("stages", json::array()))
                if (stage.at(0) == "gpu levels") wall = stage.at(1).get<double>();
            std::string levels;
            for (const auto& l : r->value("levels_last_frame", json::array())) {
                std::string items;
                for (const auto& n : l.value("items", json::array()))
                    items += (items.empty() ? "" : " → ") + count(n.get<double>());
                const double idle = l.value("idle_iterations", 0.0);
                if (idle > 0) items += " (+" + count(idle) + " idle)";
                // A level run ahead (no read-back of its own, not deferred), marked as such.
                const bool ahead = l.value("blocking_read_backs", 0.0) == 0 && l.value("draws", 0.0) > 0 &&
                                   !l.value("deferred", false);
                levels += (levels.empty() ? "" : "; ") + l.value("name", std::string()) + " " + items + ", " +
                          ms(l.value("cpu_ms", 0.0)) + " / " +
                          (l.contains("gpu_ms") ? ms(l.value("gpu_ms", 0.0)) : "–") + (ahead ? " ahead" : "");
                if (l.value("exact_gpu_ms", 0.0) > 0.0)
                    levels += " (exact stage " + ms(l.value("exact_gpu_ms", 0.0)) + " of the GPU ms)";
                // Set-up split into sending (GL calls) and building on the CPU, where the record has it.
                if (l.contains("setup_ms"))
                    levels += " (set-up " + ms(l.value("setup_ms", 0.0)) +
                              (l.contains("setup_send_ms") ? " of which sending " + ms(l.value("setup_send_ms", 0.0)) +
                                                                 ", " + count(l.value("records", 0.0)) + " records"
                                                           : std::string()) +
                              ", waiting " + ms(l.value("wait_ms", 0.0)) + ")";
            }
            rows << "| " << scene << " | " << decision << " | " << cpuTrial << " | " << gpuTrial << " | " << e
                 << " | " << ms(wall) << " | "
                 << (number(*r, "gpu_timer_ms_median") ? ms(*number(*r, "gpu_timer_ms_median")) : "–") << " | "
                 << optCount(*r, "draws_median") << " / " << optCount(*r, "blocking_read_backs_median")
                 << (number(*r, "draws_max") ? " (" + optCount(*r, "draws_max") + " / " +
                                                   optCount(*r, "blocking_read_backs_max") + ")"
                                             : std::string())
                 << " | "
                 << levels << " |\n";
        }
    }
    m_md << (rows.str().empty() ? "| – | (these records predate the measured `Auto` decision) | | | | | | | |\n"
                                : rows.str())
         << "\n";
}

namespace {

/// Median of a per-frame array over the frames where `keep` holds (by index); 0 when none.
template <class Keep>
double medianWhere(const json& values, Keep keep) {
    std::vector<double> v;
    for (std::size_t i = 0; i < values.size(); ++i)
        if (keep(i)) v.push_back(values[i].get<double>());
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// "n threads, X ms" of the record's threads named (or, with `others`, not named) cullide-worker.
std::string threadCpu(const json& r, bool workers) {
    std::size_t n = 0;
    double cpu = 0.0, busiest = 0.0;
    for (const auto& g : r.value("process_threads", json::array())) {
        if ((g.value("name", std::string()) == "cullide-worker") != workers) continue;
        n += g.value("threads", std::size_t{0});
        cpu += g.value("cpu_ms", 0.0);
        busiest = std::max(busiest, g.value("cpu_ms_max", 0.0));
    }
    // /proc counts CPU time in clock ticks (10 ms): whole milliseconds.
    if (n == 0) return "–";
    return count(static_cast<double>(n)) + " / " + fixed(cpu, 0) + " (busiest " + fixed(busiest, 0) + ")";
}

/// A record's pool loops, wake-ups and caller sleeps per frame (means), or "–" where it predates them.
std::string poolWaits(const json& r) {
    if (!r.contains("pool_calls_mean")) return "–";
    return fixed(r.value("pool_calls_mean", 0.0), 1) + " / " + fixed(r.value("pool_worker_wakes_mean", 0.0), 2) +
           " / " + fixed(r.value("pool_caller_sleeps_mean", 0.0), 2);
}

}  // namespace

void ReportWriter::threads(const Class& c) {
    m_md << "### 6. CPU frames, page faults and threads (" << c.name << ")\n\n"
            "`Auto`'s CPU-path frames (the timed frames without GPU levels) beside the CPU path alone "
            "(`cullide-cpu`), same scene and frames: median frame ms, the exact stage's in brackets, and minor page "
            "faults per frame (memory touched for the first time: a few per frame in a steady state). Threads: the "
            "culler's workers (`cullide-worker`) and every other thread of the process (the main thread, a GL "
            "driver's): count / CPU ms over the whole run (busiest thread), from `/proc` at the end of the run. Pool: "
            "`cullide-cpu`'s parallel loops per frame handed to the workers, and of those waits the wake-ups of "
            "sleeping workers and the caller's own sleeps (`Stats::poolCalls`, `poolWorkerWakes`, "
            "`poolCallerSleeps`; means over the timed frames).\n\n"
            "| scene | Auto, CPU frames: ms (exact) | faults | cullide-cpu: ms (exact) | faults | cullide-cpu: pool "
            "loops / wake-ups / caller sleeps | Auto: workers | Auto: other threads |\n"
            "|---|---|---|---|---|---|---|---|\n";
    std::ostringstream rows;
    for (const auto& scene : scenes(c, "side")) {
        const json* a = find(c, "side", scene, "cullide");
        const json* p = find(c, "side", scene, "cullide-cpu");
        if (a == nullptr || p == nullptr || !a->contains("frame_ms") || !p->contains("frame_ms")) continue;
        auto frames = [](const json& r, bool cpuOnly) {
            const json& stages = r.at("stage_frame_ms");
            const json gpu = stages.value("gpu levels", json::array());
            auto cpuFrame = [&](std::size_t i) { return !cpuOnly || i >= gpu.size() || gpu[i].get<double>() == 0.0; };
            std::size_t kept = 0;
            for (std::size_t i = 0; i < r.at("frame_ms").size(); ++i) kept += cpuFrame(i) ? 1 : 0;
            if (kept == 0) return std::string("– (every timed frame ran the GPU levels) | –");
            return ms(medianWhere(r.at("frame_ms"), cpuFrame)) + " (" +
                   ms(medianWhere(stages.value("exact", json::array()), cpuFrame)) + ") | " +
                   count(medianWhere(r.value("frame_minor_faults", json::array()), cpuFrame));
        };
        rows << "| " << scene << " | " << frames(*a, true) << " | " << frames(*p, false) << " | " << poolWaits(*p)
             << " | " << threadCpu(*a, true) << " | " << threadCpu(*a, false) << " |\n";
    }
    m_md << (rows.str().empty() ? "| – | (these records predate the per-frame figures) | | | | | | |\n" : rows.str())
         << "\n";
    m_md << "The CULLIDE engines with `--threads N` (`Settings::threads`; 0 is every core), each its own process on "
            "the same frames: median ms per frame, the exact stage's in brackets.\n\n";
    std::set<int> counts;
    std::vector<std::pair<std::string, std::string>> rowKeys;
    for (const auto& r : c.records) {
        if (r.value("tag", "") != "threads" || !r.contains("ms")) continue;
        counts.insert(r.value("threads", 0));
        const auto key = std::make_pair(r.value("scene", std::string()), r.value("engine", std::string()));
        if (std::find(rowKeys.begin(), rowKeys.end(), key) == rowKeys.end()) rowKeys.push_back(key);
    }
    if (counts.empty()) {
        m_md << "(no `threads` records in this run)\n\n";
        return;
    }
    m_md << "| scene | engine |";
    for (int n : counts) m_md << " " << n << (n == 1 ? " thread" : " threads") << " |";
    m_md << "\n|---|---|";
    for (std::size_t i = 0; i < counts.size(); ++i) m_md << "---|";
    m_md << "\n";
    for (const auto& [scene, engine] : rowKeys) {
        m_md << "| " << scene << " | " << engine << " |";
        for (int n : counts) {
            const json* hit = nullptr;
            for (const auto& r : c.records)
                if (r.value("tag", "") == "threads" && r.value("scene", "") == scene &&
                    r.value("engine", "") == engine && r.value("threads", 0) == n && r.contains("ms"))
                    hit = &r;
            std::string exact;
            if (hit != nullptr)
                for (const auto& stage : hit->value("stages", json::array()))
                    if (stage.at(0) == "exact") exact = " (" + ms(stage.at(1).get<double>()) + ")";
            m_md << " " << (hit != nullptr ? ms(medianMs(*hit)) + exact : std::string("–")) << " |";
        }
        m_md << "\n";
    }
    m_md << "\n";
}

void ReportWriter::gpuComparison() {
    m_md << "## CPU-only and GPU side by side\n\n";
    const Class* cpu = nullptr;
    const Class* gpu = nullptr;
    for (const auto& c : m_classes) (c.name == "gpu" ? gpu : cpu) = &c;
    if (cpu == nullptr || gpu == nullptr) {
        m_md << "Only the " << (gpu != nullptr ? "GPU" : "CPU-only") << " results exist so far. The same command "
                "on a machine with an NVIDIA GPU (`scripts/bench.sh`) picks the hardware EGL device, records the "
                "renderer and driver, files its results as `docs/bench/results-gpu.json` and this section then "
                "lists both side by side.\n\n";
        return;
    }
    m_md << "| scene | engine | CPU-only ms | GPU machine ms |\n|---|---|---|---|\n";
    for (const auto& scene : kSceneOrder)
        for (const auto& e : kEngineOrder) {
            const json* a = find(*cpu, "side", scene, e);
            const json* b = find(*gpu, "side", scene, e);
            if (a == nullptr && b == nullptr) continue;
            m_md << "| " << scene << " | " << e << " | " << (a ? ms(medianMs(*a)) : "–") << " | "
                 << (b ? ms(medianMs(*b)) : "–") << " |\n";
        }
    m_md << "\n";
}

}  // namespace cullide::bench
