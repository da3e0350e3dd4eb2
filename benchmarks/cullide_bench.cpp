// Runs the culler over frames of a shared scene and prints per-stage timings and set sizes.
//   cullide-bench --scene env1|env2|env3|env3-deform [--frames N] [--mode reliable|sampled] [--resolution N]
//                 [--pipeline auto|paper] [--group K] [--check] [--csv FILE]
// --check compares every frame with the brute-force reference and reports missed pairs.
#include "cullide/Culler.h"
#include "cullide/scenes/Environments.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <string>
#include <vector>

namespace {

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

std::set<std::array<std::uint32_t, 4>> flatten(const cullide::Result& r) {
    std::set<std::array<std::uint32_t, 4>> out;
    for (const auto& p : r.pairs)
        for (const auto& t : p.triangles) out.insert({p.a, t.a, p.b, t.b});
    return out;
}

int usage(const char* why) {
    std::fprintf(stderr, "cullide-bench: %s\nusage: cullide-bench --scene env1|env2|env3|env3-deform [--frames N] "
                         "[--mode reliable|sampled] [--resolution N] [--pipeline auto|paper] [--group K] [--check] "
                         "[--csv FILE]\n", why);
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    std::string scene = "env1";
    std::string csvPath;
    int frames = 20;
    bool check = false;
    cullide::Settings settings;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string { return i + 1 < argc ? argv[++i] : ""; };
        if (a == "--scene") scene = value();
        else if (a == "--frames") frames = std::atoi(value().c_str());
        else if (a == "--mode") settings.mode = value() == "sampled" ? cullide::Mode::Sampled : cullide::Mode::Reliable;
        else if (a == "--resolution") settings.resolution = std::atoi(value().c_str());
        else if (a == "--pipeline") settings.pipeline = value() == "paper" ? cullide::Pipeline::Paper : cullide::Pipeline::Auto;
        else if (a == "--backend") settings.backend = value() == "raster" ? cullide::Backend::Raster : cullide::Backend::Compute;
        else if (a == "--gpu-levels") {
            const std::string v = value();
            settings.gpuLevels = v == "always" ? cullide::GpuLevels::Always
                               : v == "never"  ? cullide::GpuLevels::Never
                                               : cullide::GpuLevels::Auto;
        }
        else if (a == "--exact-threshold") settings.exactThreshold = std::strtoull(value().c_str(), nullptr, 10);
        else if (a == "--iterations") settings.maxIterations = std::atoi(value().c_str());
        else if (a == "--group") settings.groupSize = std::atoi(value().c_str());
        else if (a == "--check") check = true;
        else if (a == "--csv") csvPath = value();
        else return usage(("unknown argument " + a).c_str());
    }
    if (frames < 1) return usage("--frames must be >= 1");
    if (const std::string e = settings.validate(); !e.empty()) return usage(e.c_str());
    std::unique_ptr<cullide::scenes::Environment> env;
    bool standIns = false;
    if (scene == "env1") env = cullide::scenes::makeEnv1(1);
    else if (scene == "env2") env = cullide::scenes::makeEnv2(1);
    else if (scene == "env3") env = cullide::scenes::makeEnv3(cullide::scenes::defaultDataDir(), false, &standIns);
    else if (scene == "env3-deform") env = cullide::scenes::makeEnv3(cullide::scenes::defaultDataDir(), true, &standIns);
    else return usage(("unknown scene " + scene).c_str());
    if (standIns) std::fprintf(stderr, "cullide-bench: real meshes not found, using procedural stand-ins\n");

    std::unique_ptr<cullide::Culler> culler;
    try {
        culler = cullide::createGpuCuller(settings);
    } catch (const cullide::GlUnavailableError& e) {
        std::fprintf(stderr, "cullide-bench: %s\n", e.what());
        return 3;
    }
    auto reference = cullide::createReferenceCuller(settings);
    std::ofstream csv;
    if (!csvPath.empty()) {
        csv.open(csvPath);
        csv << "frame,objects,triangles,prepass_groups_out,level_items,candidate_pairs,intersecting,missed,prepass_ms,"
               "upload_ms,gpu_levels_ms,exact_ms,total_ms\n";
    }
    std::vector<double> prepass, upload, levels, exact, total;
    std::size_t missed = 0, expectedPairs = 0;
    cullide::Result result, truth;
    for (int f = 0; f < frames; ++f) {
        const auto& meshes = env->frame(f);
        std::vector<cullide::Object> objects(meshes.size());
        for (std::size_t i = 0; i < meshes.size(); ++i) objects[i].mesh = &meshes[i];
        culler->run(objects, result);
        const cullide::Stats& s = result.stats;
        std::size_t frameMissed = 0;
        if (check) {
            reference->run(objects, truth);
            const auto want = flatten(truth);
            const auto got = flatten(result);
            for (const auto& p : want) frameMissed += got.count(p) ? 0 : 1;
            missed += frameMissed;
            expectedPairs += want.size();
        }
        std::string levelItems;
        for (const auto& l : s.levels) {
            levelItems += l.name + ":";
            for (std::size_t n : l.itemsPerIteration) levelItems += std::to_string(n) + "/";
            char ms[64];
            std::snprintf(ms, sizeof ms, "(%.1f ms) ", l.cpuMs);
            levelItems += ms;
        }
        if (csv) {
            csv << f << ',' << s.objects << ',' << s.triangles << ',' << s.prepassGroupsOut << ",\"" << levelItems
                << "\"," << s.candidateTrianglePairs << ',' << s.intersectingTrianglePairs << ',' << frameMissed << ','
                << s.prepassMs << ',' << s.uploadMs << ',' << s.gpuLevelsMs << ',' << s.exactMs << ',' << s.totalMs
                << '\n';
        }
        if (f == 0) {  // the first frame compiles shaders: report it separately
            std::printf("first frame: %.1f ms (shader compilation included)\n", s.totalMs);
            continue;
        }
        prepass.push_back(s.prepassMs);
        upload.push_back(s.uploadMs);
        levels.push_back(s.gpuLevelsMs);
        exact.push_back(s.exactMs);
        total.push_back(s.totalMs);
        if (f == frames - 1) {
            std::printf("last frame: objects %zu, triangles %zu, prepass objects %zu->%zu groups %zu->%zu, levels %s\n",
                        s.objects, s.triangles, s.prepassObjectsIn, s.prepassObjectsOut, s.prepassGroupsIn,
                        s.prepassGroupsOut, levelItems.c_str());
            std::printf("  candidates %zu, intersecting %zu, draws %zu, uploaded %zu B, read back %zu B\n",
                        s.candidateTrianglePairs, s.intersectingTrianglePairs, s.draws, s.bytesUploaded,
                        s.bytesReadBack);
        }
    }
    std::printf("scene %s mode %s res %d pipeline %s group %d frames %d | renderer %s\n", scene.c_str(),
                settings.mode == cullide::Mode::Reliable ? "reliable" : "sampled", settings.resolution,
                settings.pipeline == cullide::Pipeline::Auto ? "auto" : "paper", settings.groupSize, frames,
                result.stats.renderer.c_str());
    std::printf("median ms: prepass %.2f upload %.2f gpu-levels %.2f exact %.2f total %.2f (max total %.2f)\n",
                median(prepass), median(upload), median(levels), median(exact), median(total),
                total.empty() ? 0.0 : *std::max_element(total.begin(), total.end()));
    if (check) std::printf("missed triangle pairs: %zu of %zu\n", missed, expectedPairs);
    return 0;
}
