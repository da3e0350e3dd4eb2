// cullide-pairs: runs the GPU culler once on a scene file and prints the colliding pairs as JSON.
//
//   cullide-pairs SCENE.json [--mode reliable|sampled] [--resolution N] [--margin D] [--out FILE]
//                 [--gpu-levels auto|always|never] [--device-exact on-hardware|always|never]
//                 [--pipeline auto|paper] [--backend compute|raster] [--help]
//
// Exit status: 0 success, 1 unexpected failure, 2 bad input or flags, 3 no usable EGL/OpenGL where GPU levels are
// demanded (--gpu-levels always, --pipeline paper); otherwise the CPU path runs without GL.
#include "cullide/Culler.h"
#include "cullide/io/MeshIO.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
constexpr int kExitNoGl = 3;

const char* const kUsage =
    "usage: cullide-pairs SCENE.json [--mode reliable|sampled] [--resolution N] [--margin D] [--out FILE]\n"
    "\n"
    "Runs the CULLIDE GPU culler once on SCENE.json and prints the result as JSON.\n"
    "\n"
    "  SCENE.json          {\"objects\": [{\"mesh\": \"a.off\", \"transform\": [16 numbers, row-major]}, ...]};\n"
    "                      mesh paths (.off, .obj) are relative to the scene file, transform is optional\n"
    "  --mode M            reliable (default: never misses a contact) or sampled (the paper's rasterization)\n"
    "  --resolution N      image-space resolution per view, 16..4096 (default 256)\n"
    "  --margin D          also report triangle pairs closer than D >= 0 (default 0)\n"
    "  --out FILE          write the JSON to FILE instead of standard output\n"
    "  --gpu-levels L      auto (default: on a hardware GL device, GPU levels where a bounded trial of both\n"
    "                      paths shows they pay; on a software renderer the CPU path, no GL context), always,\n"
    "                      never\n"
    "  --device-exact E    with GPU levels, the exact stage's candidate search and float filter on the GPU:\n"
    "                      on-hardware (default: on a hardware GL device), always, never\n"
    "  --pipeline P        auto (default: CPU box pre-pass, group boxes, triangles) or paper\n"
    "  --backend B         compute (default) or raster\n"
    "  --help              show this help\n"
    "\n"
    "Output: {\"objects\": N, \"object_pairs\": [[i, j], ...], \"triangle_pairs\": [[i, ti, j, tj], ...],\n"
    "         \"potential_pairs\": [[i, j], ...], \"stats\": {...}, \"rejected\": [{\"object\": i, \"message\": \"...\"}]}\n"
    "object_pairs have at least one triangle pair; i < j; triangle pairs are listed once, sorted.\n"
    "\n"
    "Exit status: 0 success, 1 unexpected failure, 2 bad input or flags, 3 no usable EGL/OpenGL with\n"
    "--gpu-levels always or --pipeline paper (otherwise the CPU path runs without GL, with a notice).\n";

class UsageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct Options {
    std::string scene;
    std::string out;
    cullide::Settings settings;
};

int parseIntFlag(const std::string& flag, const std::string& value) {
    int v = 0;
    const char* end = value.data() + value.size();
    auto [ptr, ec] = std::from_chars(value.data(), end, v);
    if (value.empty() || ptr != end || ec != std::errc()) {
        throw UsageError(flag + " expects an integer, got '" + value + "'");
    }
    return v;
}

double parseDoubleFlag(const std::string& flag, const std::string& value) {
    double v = 0.0;
    const char* end = value.data() + value.size();
    auto [ptr, ec] = std::from_chars(value.data(), end, v);
    if (value.empty() || ptr != end || ec != std::errc() || !std::isfinite(v)) {
        throw UsageError(flag + " expects a finite number, got '" + value + "'");
    }
    return v;
}

/// Returns nullopt when --help was given.
std::optional<Options> parseArgs(int argc, char** argv) {
    Options o;
    bool haveScene = false;
    for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "--help" || arg == "-h") return std::nullopt;
        if (arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
            std::string flag = arg, value;
            bool inlineValue = false;
            if (const auto eq = arg.find('='); eq != std::string::npos) {
                flag = arg.substr(0, eq);
                value = arg.substr(eq + 1);
                inlineValue = true;
            }
            if (flag != "--mode" && flag != "--resolution" && flag != "--margin" && flag != "--out" &&
                flag != "--gpu-levels" && flag != "--device-exact" && flag != "--pipeline" && flag != "--backend") {
                throw UsageError("unknown option '" + flag + "'");
            }
            if (!inlineValue) {
                if (i + 1 >= argc) throw UsageError(flag + " needs a value");
                value = argv[++i];
            }
            if (flag == "--mode") {
                if (value == "reliable") {
                    o.settings.mode = cullide::Mode::Reliable;
                } else if (value == "sampled") {
                    o.settings.mode = cullide::Mode::Sampled;
                } else {
                    throw UsageError("--mode expects 'reliable' or 'sampled', got '" + value + "'");
                }
            } else if (flag == "--resolution") {
                o.settings.resolution = parseIntFlag(flag, value);
            } else if (flag == "--margin") {
                o.settings.margin = parseDoubleFlag(flag, value);
            } else if (flag == "--gpu-levels") {
                if (value == "auto") o.settings.gpuLevels = cullide::GpuLevels::Auto;
                else if (value == "always") o.settings.gpuLevels = cullide::GpuLevels::Always;
                else if (value == "never") o.settings.gpuLevels = cullide::GpuLevels::Never;
                else throw UsageError("--gpu-levels expects 'auto', 'always' or 'never', got '" + value + "'");
            } else if (flag == "--device-exact") {
                if (value == "on-hardware") o.settings.deviceExact = cullide::DeviceExact::OnHardware;
                else if (value == "always") o.settings.deviceExact = cullide::DeviceExact::Always;
                else if (value == "never") o.settings.deviceExact = cullide::DeviceExact::Never;
                else throw UsageError("--device-exact expects 'on-hardware', 'always' or 'never', got '" + value + "'");
            } else if (flag == "--pipeline") {
                if (value == "auto") o.settings.pipeline = cullide::Pipeline::Auto;
                else if (value == "paper") o.settings.pipeline = cullide::Pipeline::Paper;
                else throw UsageError("--pipeline expects 'auto' or 'paper', got '" + value + "'");
            } else if (flag == "--backend") {
                if (value == "compute") o.settings.backend = cullide::Backend::Compute;
                else if (value == "raster") o.settings.backend = cullide::Backend::Raster;
                else throw UsageError("--backend expects 'compute' or 'raster', got '" + value + "'");
            } else {
                if (value.empty()) throw UsageError("--out needs a file name");
                o.out = value;
            }
        } else if (arg.size() > 1 && arg[0] == '-') {
            throw UsageError("unknown option '" + arg + "'");
        } else {
            if (haveScene) throw UsageError("more than one scene file given ('" + o.scene + "', '" + arg + "')");
            o.scene = arg;
            haveScene = true;
        }
    }
    if (!haveScene) throw UsageError("no scene file given");
    return o;
}

/// A GPU time from timer queries, or null where the driver gave none that is plausible (Stats::gpuTimingValid).
nlohmann::ordered_json gpuTime(double ms, bool valid) {
    return valid ? nlohmann::ordered_json(ms) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json statsToJson(const cullide::Stats& s) {
    nlohmann::ordered_json j;
    j["renderer"] = s.renderer;
    j["device"] = s.device;
    if (!s.gpuUnavailable.empty()) j["gpu_unavailable"] = s.gpuUnavailable;
    j["objects"] = s.objects;
    j["triangles"] = s.triangles;
    j["rejected_objects"] = s.rejectedObjects;
    j["prepass_objects_in"] = s.prepassObjectsIn;
    j["prepass_objects_out"] = s.prepassObjectsOut;
    j["prepass_groups_in"] = s.prepassGroupsIn;
    j["prepass_groups_out"] = s.prepassGroupsOut;
    j["clusters"] = s.clusters;
    j["unrasterised_clusters"] = s.unrasterisedClusters;
    j["level_reruns"] = s.levelReruns;
    nlohmann::ordered_json levels = nlohmann::ordered_json::array();
    for (const cullide::LevelStats& l : s.levels) {
        nlohmann::ordered_json lj;
        lj["name"] = l.name;
        lj["items_per_iteration"] = l.itemsPerIteration;
        lj["primitives_drawn"] = l.primitivesDrawn;
        lj["draws"] = l.draws;
        lj["cpu_ms"] = l.cpuMs;
        lj["setup_ms"] = l.setupMs;
        lj["setup_send_ms"] = l.setupSendMs;
        lj["records"] = l.records;
        lj["record_builds"] = l.recordBuilds;
        lj["iterations"] = l.iterations;
        lj["short_builds"] = l.shortBuilds;
        lj["idle_iterations"] = l.idleIterations;
        lj["blocking_read_backs"] = l.blockingReadBacks;
        lj["wait_ms"] = l.waitMs;
        lj["deferred"] = l.deferred;
        lj["gpu_ms"] = gpuTime(l.gpuMs, l.gpuTimingValid);
        lj["exact_gpu_ms"] = gpuTime(l.exactGpuMs, l.gpuTimingValid);
        levels.push_back(std::move(lj));
    }
    j["levels"] = std::move(levels);
    j["pcs_objects"] = s.pcsObjects;
    j["candidate_object_pairs"] = s.candidateObjectPairs;
    j["candidate_triangle_pairs"] = s.candidateTrianglePairs;
    j["exact_tests"] = s.exactTests;
    j["device_exact_pairs"] = s.deviceExactPairs;
    j["device_exact_certified"] = s.deviceExactCertified;
    j["device_exact_overflows"] = s.deviceExactOverflows;
    j["exact_trees_refit"] = s.exactTreesRefit;
    j["exact_trees_sorted"] = s.exactTreesSorted;
    j["exact_trees_whole"] = s.exactTreesWhole;
    j["exact_trees_kept"] = s.exactTreesKept;
    j["mesh_orders_computed"] = s.meshOrdersComputed;
    j["intersecting_triangle_pairs"] = s.intersectingTrianglePairs;
    j["draws"] = s.draws;
    j["bytes_uploaded"] = s.bytesUploaded;
    j["bytes_read_back"] = s.bytesReadBack;
    j["blocking_read_backs"] = s.blockingReadBacks;
    j["prepass_ms"] = s.prepassMs;
    j["upload_ms"] = s.uploadMs;
    j["gpu_levels_ms"] = s.gpuLevelsMs;
    j["gpu_ms"] = gpuTime(s.gpuMs, s.gpuTimingValid);
    j["upload_gpu_ms"] = gpuTime(s.uploadGpuMs, s.gpuTimingValid);
    j["exact_ms"] = s.exactMs;
    j["total_ms"] = s.totalMs;
    return j;
}

/// One top-level key per line, each value compact (pair lists can be long).
std::string formatOutput(const nlohmann::ordered_json& doc) {
    std::string s = "{\n";
    bool first = true;
    for (auto it = doc.begin(); it != doc.end(); ++it) {
        if (!first) s += ",\n";
        first = false;
        s += "  ";
        s += nlohmann::ordered_json(it.key()).dump();
        s += ": ";
        s += it.value().dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
    }
    s += "\n}\n";
    return s;
}

nlohmann::ordered_json buildOutput(std::size_t objectCount, const cullide::Result& result) {
    std::vector<std::array<std::uint32_t, 2>> potential, colliding;
    std::vector<std::array<std::uint32_t, 4>> triangles;
    for (const cullide::ObjectPair& p : result.pairs) {
        const bool swap = p.a > p.b;
        const std::uint32_t i = swap ? p.b : p.a, j = swap ? p.a : p.b;
        potential.push_back({i, j});
        if (!p.hasTriangles || p.triangles.empty()) continue;
        colliding.push_back({i, j});
        for (const cullide::TrianglePair& t : p.triangles) {
            triangles.push_back(swap ? std::array<std::uint32_t, 4>{i, t.b, j, t.a}
                                     : std::array<std::uint32_t, 4>{i, t.a, j, t.b});
        }
    }
    auto sortUnique = [](auto& v) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
    };
    sortUnique(potential);
    sortUnique(colliding);
    sortUnique(triangles);

    nlohmann::ordered_json doc;
    doc["objects"] = objectCount;
    doc["object_pairs"] = colliding;
    doc["triangle_pairs"] = triangles;
    doc["potential_pairs"] = potential;
    doc["stats"] = statsToJson(result.stats);
    nlohmann::ordered_json rejected = nlohmann::ordered_json::array();
    for (const cullide::ObjectDiagnostic& d : result.rejected) {
        rejected.push_back({{"object", d.object}, {"message", d.message}});
    }
    doc["rejected"] = std::move(rejected);
    return doc;
}

int run(int argc, char** argv) {
    std::optional<Options> options;
    try {
        options = parseArgs(argc, argv);
    } catch (const UsageError& e) {
        std::cerr << "cullide-pairs: " << e.what() << "\n(run 'cullide-pairs --help' for usage)\n";
        return kExitUsage;
    }
    if (!options) {
        std::cout << kUsage;
        return kExitOk;
    }
    if (const std::string err = options->settings.validate(); !err.empty()) {
        std::cerr << "cullide-pairs: invalid settings: " << err << "\n";
        return kExitUsage;
    }

    std::vector<cullide::io::SceneObject> scene;
    try {
        scene = cullide::io::readSceneFile(options->scene);
    } catch (const cullide::io::ParseError& e) {
        std::cerr << "cullide-pairs: " << e.what() << "\n";
        return kExitUsage;
    }
    std::vector<cullide::Object> objects(scene.size());
    for (std::size_t i = 0; i < scene.size(); ++i) {  // each file's mesh once, placed by its transform
        objects[i].mesh = scene[i].mesh.get();
        if (!scene[i].transform.isIdentity(0.0)) objects[i].transform = &scene[i].toWorld;
    }

    // Open the output before the (possibly long) run, so a bad path fails fast.
    std::ofstream file;
    if (!options->out.empty()) {
        file.open(options->out, std::ios::binary | std::ios::trunc);
        if (!file) {
            std::cerr << "cullide-pairs: cannot write '" << options->out << "'\n";
            return kExitUsage;
        }
    }

    cullide::Result result;
    try {
        const std::unique_ptr<cullide::Culler> culler = cullide::createGpuCuller(options->settings);
        culler->run(objects, result);
    } catch (const cullide::GlUnavailableError& e) {
        std::cerr << "cullide-pairs: no usable EGL/OpenGL: " << e.what() << "\n";
        return kExitNoGl;
    } catch (const std::invalid_argument& e) {
        std::cerr << "cullide-pairs: " << e.what() << "\n";
        return kExitUsage;
    }

    const std::string text = formatOutput(buildOutput(objects.size(), result));
    std::ostream& out = options->out.empty() ? static_cast<std::ostream&>(std::cout) : file;
    out << text;
    out.flush();
    if (!out) {
        std::cerr << "cullide-pairs: error writing the output\n";
        return kExitFailure;
    }
    return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::cerr << "cullide-pairs: " << e.what() << "\n";
        return kExitFailure;
    }
}
