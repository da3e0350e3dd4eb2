// cullide-demo: the breakable-object demo (the paper's Fig. 6) and the paper's three environments, headless.
//
//   cullide-demo [--scene breakable|env1|env2|env3] [--frames N] [--resolution N] [--mode reliable|sampled]
//                [--seed S] [--out DIR] [--snapshot-every K] [--check-every K] [--mesh PATH]
//                [--breakable-mesh PATH] [--objects N] [--pipeline P] [--culling auto|on|off]
//                [--deep-penetration-fallback on|off]
//                [--quiet] [--help]
//
// Writes DIR/frames.csv (one row per frame), DIR/summary.json, DIR/snapshots/frame_NNNN.png every K frames and
// DIR/contact_sheet.png. Exit status: 0 success, 1 reference check failed (a missed pair in reliable mode) or
// unexpected failure, 2 bad flags, 3 no usable EGL/OpenGL, 4 unreadable mesh or unwritable output.
#include "FrameLog.h"
#include "SceneRunner.h"

#include "cullide/Timer.h"
#include "cullide/io/Image.h"
#include "cullide/io/MeshIO.h"
#include "cullide/io/Snapshot.h"

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
constexpr int kExitNoGl = 3;
constexpr int kExitInput = 4;

const char* const kUsage =
    "usage: cullide-demo [--scene breakable|env1|env2|env3] [--frames N] [--resolution N] [--mode reliable|sampled]\n"
    "                    [--seed S] [--out DIR] [--snapshot-every K] [--check-every K] [--mesh PATH]\n"
    "                    [--breakable-mesh PATH] [--objects N] [--pipeline P]\n"
    "                    [--culling auto|on|off] [--deep-penetration-fallback on|off]\n"
    "                    [--quiet] [--help]\n"
    "\n"
    "Runs a CULLIDE scene headless and writes per-frame figures, a summary and snapshots.\n"
    "\n"
    "  --scene S           breakable (default): the bunny falls through the dragon, which breaks on impact\n"
    "                      (Bullet dynamics with CullideBroadphase + CullideCollisionDispatcher);\n"
    "                      env1: 100 deforming open cylinders x 200 triangles; env2: 6 deforming tori x 20K;\n"
    "                      env3: bunny vs dragon interpenetrating (rigid)\n"
    "  --frames N          frames to run (default: breakable 150, env1 100, env2 30, env3 60)\n"
    "  --resolution N      image-space resolution per view, 16..4096 (default 256)\n"
    "  --mode M            reliable (default: never misses a contact) or sampled (the paper's rasterization)\n"
    "  --seed S            scene seed (fracture sites, environment motion); same seed, same run (default 1)\n"
    "  --out DIR           output directory (default out/demo)\n"
    "  --snapshot-every K  PNG snapshot every K frames, 0 = none (default 10)\n"
    "  --check-every K     compare every K-th frame with the exact brute-force reference, 0 = never (default 0)\n"
    "  --mesh PATH         OFF/OBJ for the falling object (breakable)\n"
    "  --breakable-mesh P  OFF/OBJ for the breakable object (breakable)\n"
    "  --objects N         object count for env1 / env2 (default 100 / 6)\n"
    "  --pipeline P        breakable: cullide (default), bullet-dbvt or bullet-axis-sweep (Bullet's own\n"
    "                      broadphase and dispatcher with GImpact, for comparison)\n"
    "  --culling auto|on|off\n"
    "                      breakable, cullide: the broadphase's culling switches. auto (default): the\n"
    "                      pieces' pairs go through the culler where a trial shows it pays, which needs a\n"
    "                      hardware GL device (elsewhere they get Bullet's GImpact contacts bit for bit, at a\n"
    "                      fraction of its cost); on: always through the culler (its CPU path or its GPU\n"
    "                      levels, as the culler decides); off: never. frames.csv says per frame which path\n"
    "                      ran. --gimpact-pair-culling on|off is the same as --culling on|off\n"
    "  --deep-penetration-fallback on|off\n"
    "                      breakable, cullide, pairs culled: intersecting GImpact pairs get Bullet's\n"
    "                      contacts (default on); off, fewer contacts between interpenetrating pieces\n"
    "  --quiet             no progress line\n"
    "  --help              show this help\n"
    "\n"
    "Meshes: the real bunny, dragon and armadillo are put in data/meshes by scripts/fetch_meshes.sh (from Debian's\n"
    "libcgal-demo); without them procedural stand-ins are used and a notice is printed.\n"
    "Exit status: 0 success, 1 a missed pair in reliable mode or an unexpected failure, 2 bad flags,\n"
    "3 no usable EGL/OpenGL, 4 unreadable mesh or unwritable output.\n";

class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// An output file could not be written (exit 4).
class OutputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

void writeOutputPng(const std::string& path, const cullide::Image& image) {
    try {
        cullide::io::writePng(path, image);
    } catch (const std::exception& e) {
        throw OutputError(e.what());
    }
}

struct Options {
    cullide::demo::RunnerOptions runner;
    int frames = -1;
    std::string out = "out/demo";
    int snapshotEvery = 10;
    int checkEvery = 0;
    bool quiet = false;
};

long long parseInteger(const std::string& flag, const std::string& value, long long lo, long long hi) {
    long long v = 0;
    const char* end = value.data() + value.size();
    auto [ptr, ec] = std::from_chars(value.data(), end, v);
    if (value.empty() || ptr != end || ec != std::errc() || v < lo || v > hi)
        throw UsageError(flag + " expects an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                         ", got '" + value + "'");
    return v;
}

Options parse(int argc, char** argv, bool& help) {
    Options o;
    bool fallbackGiven = false;
    bool cullingGiven = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw UsageError(a + " needs a value");
            return argv[++i];
        };
        auto onOff = [&]() {
            const std::string v = value();
            if (v != "on" && v != "off") throw UsageError(a + " expects on or off, got '" + v + "'");
            return v == "on";
        };
        if (a == "--help" || a == "-h") {
            help = true;
        } else if (a == "--scene") {
            o.runner.scene = value();
            if (o.runner.scene != "breakable" && o.runner.scene != "env1" && o.runner.scene != "env2" &&
                o.runner.scene != "env3")
                throw UsageError("--scene expects breakable, env1, env2 or env3, got '" + o.runner.scene + "'");
        } else if (a == "--frames") {
            o.frames = int(parseInteger(a, value(), 1, 1000000));
        } else if (a == "--resolution") {
            o.runner.culler.resolution = int(parseInteger(a, value(), 16, 4096));
        } else if (a == "--mode") {
            const std::string m = value();
            if (m == "reliable") o.runner.culler.mode = cullide::Mode::Reliable;
            else if (m == "sampled") o.runner.culler.mode = cullide::Mode::Sampled;
            else throw UsageError("--mode expects reliable or sampled, got '" + m + "'");
        } else if (a == "--seed") {
            o.runner.seed = std::uint64_t(parseInteger(a, value(), 0, (1LL << 62)));
        } else if (a == "--out") {
            o.out = value();
            if (o.out.empty()) throw UsageError("--out needs a directory");
        } else if (a == "--snapshot-every") {
            o.snapshotEvery = int(parseInteger(a, value(), 0, 1000000));
        } else if (a == "--check-every") {
            o.checkEvery = int(parseInteger(a, value(), 0, 1000000));
        } else if (a == "--mesh") {
            o.runner.mesh = value();
        } else if (a == "--breakable-mesh") {
            o.runner.breakableMesh = value();
        } else if (a == "--objects") {
            o.runner.objects = int(parseInteger(a, value(), 1, 100000));
        } else if (a == "--pipeline") {
            o.runner.pipeline = value();
            if (o.runner.pipeline != "cullide" && o.runner.pipeline != "bullet-dbvt" &&
                o.runner.pipeline != "bullet-axis-sweep")
                throw UsageError("--pipeline expects cullide, bullet-dbvt or bullet-axis-sweep, got '" +
                                 o.runner.pipeline + "'");
        } else if (a == "--culling") {
            const std::string m = value();
            if (m == "auto") o.runner.culling = cullide::Culling::Auto;
            else if (m == "on") o.runner.culling = cullide::Culling::On;
            else if (m == "off") o.runner.culling = cullide::Culling::Off;
            else throw UsageError("--culling expects auto, on or off, got '" + m + "'");
            cullingGiven = true;
        } else if (a == "--gimpact-pair-culling") {
            o.runner.culling = onOff() ? cullide::Culling::On : cullide::Culling::Off;
            cullingGiven = true;
        } else if (a == "--deep-penetration-fallback") {
            o.runner.deepPenetrationFallback = onOff();
            fallbackGiven = true;
        } else if (a == "--quiet") {
            o.quiet = true;
        } else {
            throw UsageError("unknown flag '" + a + "'");
        }
    }
    const std::string error = o.runner.culler.validate();
    if (!error.empty()) throw UsageError(error);
    // Flags that the chosen scene would silently ignore are mistakes.
    const bool breakable = o.runner.scene == "breakable";
    if (!breakable && (!o.runner.mesh.empty() || !o.runner.breakableMesh.empty() || o.runner.pipeline != "cullide"))
        throw UsageError("--mesh, --breakable-mesh and --pipeline apply to --scene breakable only");
    if ((fallbackGiven || cullingGiven) && (!breakable || o.runner.pipeline != "cullide"))
        throw UsageError("--culling or --deep-penetration-fallback: each applies to --scene breakable with "
                         "--pipeline cullide only");
    if (fallbackGiven && o.runner.culling == cullide::Culling::Off)
        throw UsageError("--deep-penetration-fallback applies where pairs may be culled (--culling auto or on) only");
    if (o.runner.objects > 0 && o.runner.scene != "env1" && o.runner.scene != "env2")
        throw UsageError("--objects applies to --scene env1 and env2 only");
    return o;
}

/// Distinct, muted object colours (golden-angle hues), keyed by the object's name so that an object keeps its
/// colour when others appear or disappear.
std::array<float, 3> colourOf(const std::string& name) {
    std::uint32_t i = 2166136261u;  // FNV-1a
    for (unsigned char ch : name) i = (i ^ ch) * 16777619u;
    const double h = std::fmod(0.08 + 0.618033988749895 * double(i % 1000u), 1.0) * 6.0;
    const double s = 0.35, v = 0.80;
    const double c = v * s, x = c * (1 - std::fabs(std::fmod(h, 2.0) - 1)), m = v - c;
    double r = 0, g = 0, b = 0;
    switch (int(h)) {
    case 0: r = c, g = x; break;
    case 1: r = x, g = c; break;
    case 2: g = c, b = x; break;
    case 3: g = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
    }
    return {float(r + m), float(g + m), float(b + m)};
}

/// Renders the current state: each object in its colour, its PCS triangles highlighted and its intersecting
/// triangles marked (the paper's Fig. 5(c-d)).
cullide::Image snapshot(cullide::SnapshotRenderer& renderer, cullide::demo::SceneRunner& runner,
                        const cullide::Aabb& frameBox) {
    const auto& meshes = runner.meshes();
    const cullide::Result& result = runner.cullResult();
    std::vector<std::vector<std::uint32_t>> marked(meshes.size());
    for (const cullide::ObjectPair& p : result.pairs)
        for (const cullide::TrianglePair& t : p.triangles) {
            marked[p.a].push_back(t.a);
            marked[p.b].push_back(t.b);
        }
    std::vector<cullide::SnapshotItem> items;
    std::optional<cullide::TriangleMesh> ground = runner.ground();
    if (ground) items.push_back({&*ground, {0.55f, 0.55f, 0.52f}, nullptr, nullptr});
    static const std::vector<std::uint32_t> kNone;
    const std::vector<std::string> names = runner.names();
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        std::sort(marked[i].begin(), marked[i].end());
        marked[i].erase(std::unique(marked[i].begin(), marked[i].end()), marked[i].end());
        const auto* pcs = i < result.pcsTriangles.size() ? &result.pcsTriangles[i] : &kNone;
        items.push_back({&meshes[i], colourOf(i < names.size() ? names[i] : std::to_string(i)), pcs, &marked[i]});
    }
    cullide::SnapshotView view;
    view.frame = frameBox;
    view.dimUnhighlighted = false;  // whole objects stay visible; PCS and intersecting triangles stand out
    return renderer.render(items, view);
}

std::string cpuModel() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            return colon == std::string::npos ? line : line.substr(colon + 2);
        }
    return "unknown";
}

/// What culled the frames: the setting, the frames per path (frames.csv's path column), the culled and pruned pairs,
/// and Culling::Auto's decision for the pieces' pairs (breakable) with the timings behind it.
nlohmann::json cullingSummary(const Options& o, const cullide::demo::SceneRunner& runner,
                              const std::vector<cullide::demo::FrameRecord>& records) {
    using nlohmann::json;
    json paths = json::object();
    std::size_t culled = 0, pruned = 0;
    for (const auto& r : records) {
        paths[r.path.empty() ? "none" : r.path] = paths.value(r.path.empty() ? "none" : r.path, 0) + 1;
        culled += r.culledPairs;
        pruned += r.prunedPairs;
    }
    const char* setting = o.runner.culling == cullide::Culling::Auto ? "auto"
                          : o.runner.culling == cullide::Culling::On ? "on"
                                                                     : "off";
    json summary = {{"setting", o.runner.scene == "breakable" ? setting : "culler"},
                    {"frames_by_path", paths},
                    {"culled_pair_steps", culled},
                    {"pruned_pair_steps", pruned}};
    if (const auto d = runner.cullingDecision())
        summary["auto"] = {{"state", d->state},
                           {"unculled_ms", d->unculledMs},
                           {"culled_ms", d->culledMs},
                           {"abandoned_trials", d->abandonedTrials}};
    return summary;
}

int run(const Options& o) {
    namespace fs = std::filesystem;
    using nlohmann::json;
    std::error_code ec;
    fs::create_directories(fs::path(o.out) / "snapshots", ec);
    std::ofstream csv(fs::path(o.out) / "frames.csv");
    if (ec || !csv) {
        std::fprintf(stderr, "cullide-demo: cannot write to '%s'%s%s\n", o.out.c_str(), ec ? ": " : "",
                     ec ? ec.message().c_str() : "");
        return kExitInput;
    }
    cullide::Timer wall;
    auto runner = cullide::demo::makeSceneRunner(o.runner);
    if (runner->usedStandIns())
        std::fprintf(stderr, "cullide-demo: notice: real meshes not found (run scripts/fetch_meshes.sh); using "
                             "procedural stand-ins\n");
    std::unique_ptr<cullide::SnapshotRenderer> renderer;
    if (o.snapshotEvery > 0) renderer = cullide::SnapshotRenderer::create(o.runner.culler.device);

    const int frames = o.frames > 0 ? o.frames : runner->defaultFrames();
    const bool progress = !o.quiet && isatty(fileno(stderr));
    cullide::demo::writeCsvHeader(csv);
    std::vector<cullide::demo::FrameRecord> records;
    std::vector<std::string> snapshotFiles;
    // The contact sheet: at most 12 evenly spaced snapshots of the run (the fracture sequence for the breakable
    // scene); only their thumbnails are kept.
    std::vector<cullide::Image> thumbnails;
    std::vector<std::size_t> sheetPicks;
    if (o.snapshotEvery > 0) {
        const std::size_t snapshots = std::size_t((frames - 1) / o.snapshotEvery + 1 + ((frames - 1) % o.snapshotEvery ? 1 : 0));
        const std::size_t n = std::min<std::size_t>(12, snapshots);
        for (std::size_t k = 0; k < n; ++k) sheetPicks.push_back(n == 1 ? 0 : k * (snapshots - 1) / (n - 1));
    }
    std::optional<cullide::Aabb> frameBox;
    long missedTotal = 0;
    int checked = 0;
    double renderMs = 0;
    for (int f = 0; f < frames; ++f) {
        const bool check = o.checkEvery > 0 && f % o.checkEvery == 0;
        const cullide::demo::FrameRecord r = runner->advance(check);
        records.push_back(r);
        cullide::demo::writeCsvRow(csv, r);
        if (check) {
            ++checked;
            missedTotal += r.missed;
        }
        if (renderer && (f % o.snapshotEvery == 0 || f == frames - 1)) {
            cullide::Timer t;
            if (!frameBox) {
                // Fixed camera: the first frame's bounds (with the ground for the breakable scene), grown a little.
                cullide::Aabb box;
                for (const auto& m : runner->meshes())
                    for (const auto& v : m.vertices) box.grow(v);
                if (auto g = runner->ground())
                    for (const auto& v : g->vertices) box.grow(v);
                frameBox = box.inflated(0.05 * box.extent().maxCoeff());
            }
            const cullide::Image image = snapshot(*renderer, *runner, *frameBox);
            char name[64];
            std::snprintf(name, sizeof name, "snapshots/frame_%04d.png", f);
            writeOutputPng((fs::path(o.out) / name).string(), image);
            if (std::binary_search(sheetPicks.begin(), sheetPicks.end(), snapshotFiles.size()))
                thumbnails.push_back(cullide::io::downscale(image, 2));
            snapshotFiles.push_back(name);
            renderMs += t.ms();
        }
        if (progress) {
            std::fprintf(stderr, "\r%s frame %d/%d  objects %zu  triangles %zu  triangle pairs %zu  %.1f ms   ",
                         o.runner.scene.c_str(), f + 1, frames, r.objects, r.triangles, r.trianglePairs, r.frameMs);
            std::fflush(stderr);
        }
    }
    if (progress) std::fprintf(stderr, "\n");
    csv.close();
    if (!csv) throw OutputError("cannot write " + (fs::path(o.out) / "frames.csv").string());

    std::string sheet;
    if (!thumbnails.empty()) {
        sheet = "contact_sheet.png";
        writeOutputPng((fs::path(o.out) / sheet).string(), cullide::io::makeContactSheet(thumbnails, 4));
    }

    using cullide::demo::FrameRecord;
    auto figures = [&](double FrameRecord::*column) {
        const auto f = cullide::demo::figuresOf(records, column);
        return json{{"median", f.median}, {"worst", f.worst}, {"mean", f.mean}};
    };
    std::size_t pairsTotal = 0, contactsTotal = 0;
    for (const auto& r : records) pairsTotal += r.trianglePairs, contactsTotal += r.contacts;
    json summary = {
        {"scene", o.runner.scene},
        {"frames", frames},
        {"seed", o.runner.seed},
        {"pipeline", o.runner.scene == "breakable" ? o.runner.pipeline : "culler"},
        {"deep_penetration_fallback", o.runner.deepPenetrationFallback},
        {"culling", cullingSummary(o, *runner, records)},
        {"mode", o.runner.culler.mode == cullide::Mode::Reliable ? "reliable" : "sampled"},
        {"resolution", o.runner.culler.resolution},
        {"renderer", runner->renderer()},
        {"device", runner->device()},
        {"snapshot_renderer", renderer ? renderer->renderer() : ""},
        {"machine", {{"cpu", cpuModel()}, {"cores", std::thread::hardware_concurrency()}}},
        {"stand_in_meshes", runner->usedStandIns()},
        {"fractures", runner->fractures()},
        {"objects", {{"first", records.front().objects}, {"last", records.back().objects}}},
        {"triangles", {{"first", records.front().triangles}, {"last", records.back().triangles}}},
        {"triangle_pairs_total", pairsTotal},
        {"contacts_total", contactsTotal},
        {"ms", {{"frame", figures(&FrameRecord::frameMs)}, {"cull", figures(&FrameRecord::cullMs)},
                {"prepass", figures(&FrameRecord::prepassMs)}, {"gpu_levels", figures(&FrameRecord::gpuLevelsMs)},
                {"exact", figures(&FrameRecord::exactMs)}, {"narrowphase", figures(&FrameRecord::narrowphaseMs)},
                {"solver", figures(&FrameRecord::solverMs)}, {"fracture", figures(&FrameRecord::fractureMs)}}},
        {"check", {{"frames_checked", checked}, {"missed", missedTotal}}},
        {"snapshots", snapshotFiles},
        {"snapshot_ms_total", renderMs},
        {"contact_sheet", sheet},
        {"wall_s", wall.ms() / 1000.0},
    };
    {
        std::ofstream out(fs::path(o.out) / "summary.json");
        out << summary.dump(2) << '\n';
        if (!out) throw OutputError("cannot write " + (fs::path(o.out) / "summary.json").string());
    }
    const auto frame = cullide::demo::figuresOf(records, &FrameRecord::frameMs);
    std::printf("cullide-demo: %s, %d frames, %zu -> %zu objects, %d fracture(s); ms/frame median %.2f, worst %.2f; "
                "renderer %s; output in %s\n",
                o.runner.scene.c_str(), frames, records.front().objects, records.back().objects, runner->fractures(),
                frame.median, frame.worst, runner->renderer().c_str(), o.out.c_str());
    if (checked > 0)
        std::printf("cullide-demo: checked %d frame(s) against the exact reference: %ld missed pair(s)\n", checked,
                    missedTotal);
    if (missedTotal > 0 && o.runner.culler.mode == cullide::Mode::Reliable) {
        std::fprintf(stderr, "cullide-demo: reliable mode missed %ld pair(s) against the exact reference\n",
                     missedTotal);
        return kExitFailure;
    }
    return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
    Options options;
    bool help = false;
    try {
        options = parse(argc, argv, help);
    } catch (const UsageError& e) {
        std::fprintf(stderr, "cullide-demo: %s\n%s", e.what(), kUsage);
        return kExitUsage;
    }
    if (help) {
        std::fputs(kUsage, stdout);
        return kExitOk;
    }
    try {
        return run(options);
    } catch (const cullide::GlUnavailableError& e) {
        std::fprintf(stderr, "cullide-demo: %s\n", e.what());
        return kExitNoGl;
    } catch (const cullide::io::ParseError& e) {
        std::fprintf(stderr, "cullide-demo: %s\n", e.what());
        return kExitInput;
    } catch (const OutputError& e) {
        std::fprintf(stderr, "cullide-demo: %s\n", e.what());
        return kExitInput;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "cullide-demo: %s\n", e.what());
        return kExitFailure;
    }
}
