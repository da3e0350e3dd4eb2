// A GL error in the middle of a frame (issue #6): the frame falls back to the CPU path and still reports every
// pair; the culler keeps working once the error is gone. Errors are injected with CULLIDE_INJECT_GL_ERROR (see
// plugin/src/gl/GlApi.h), which makes the named GL check report GL_INVALID_OPERATION. No GL device at all
// (issue 13): cullide-pairs runs the CPU path unless GPU levels are demanded.
#include "Compare.h"
#include "GlTestSupport.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace cullide::test {
namespace {

/// Sets an environment variable for the scope of one test.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const char* value) : m_name(name) { setenv(name, value, 1); }
    ~ScopedEnv() { unsetenv(m_name); }
    ScopedEnv(const ScopedEnv&) = delete;
    ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
    const char* m_name;
};

void expectSameAsReference(const Result& reference, const Result& result, const char* what) {
    const Comparison c = compare(reference, result);
    EXPECT_EQ(c.missed, 0u) << what << ": " << c.firstMissed;
    EXPECT_EQ(c.spurious, 0u) << what;
    EXPECT_TRUE(c.objectPairsEqual) << what;
}

TEST(GlFailure, ErrorMidFrameFallsBackWithoutMissingAPair) {
    for (Pipeline pipeline : {Pipeline::Auto, Pipeline::Paper}) {
        Settings settings;
        settings.gpuLevels = GpuLevels::Always;  // GPU levels also on llvmpipe, where Auto skips them
        settings.exactThreshold = 0;
        settings.pipeline = pipeline;
        settings.resolution = 64;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
        const auto meshes = randomSoups(11, 40, 100, 0.08);
        auto objects = asObjects(meshes);
        for (std::size_t i = 0; i < objects.size(); i += 3) objects[i].staticKey = i + 1;  // resident on the device
        Result reference, healthy, failing, recovered;
        createReferenceCuller(settings)->run(objects, reference);
        ASSERT_GT(trianglePairs(reference).size(), 0u);

        culler->run(objects, healthy);
        EXPECT_EQ(healthy.stats.gpuFallbacks, 0u);
        EXPECT_FALSE(healthy.stats.levels.empty()) << "the GPU levels must run in this test";
        expectSameAsReference(reference, healthy, "healthy");
        {
            ScopedEnv inject("CULLIDE_INJECT_GL_ERROR", "visibility iteration");
            culler->run(objects, failing);
        }
        EXPECT_EQ(failing.stats.gpuFallbacks, 1u);
        EXPECT_NE(failing.stats.gpuError.find("OpenGL error 0x0502"), std::string::npos) << failing.stats.gpuError;
        expectSameAsReference(reference, failing, "GL error mid-frame");

        culler->run(objects, recovered);  // the error is gone: the GPU levels run again
        EXPECT_EQ(recovered.stats.gpuFallbacks, 0u) << recovered.stats.gpuError;
        expectSameAsReference(reference, recovered, "after the error");
    }
}

TEST(GlFailure, InjectionOnlyMatchesTheNamedCheck) {
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;
    settings.exactThreshold = 0;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    const auto meshes = randomSoups(12, 6, 40, 0.3);
    Result result;
    ScopedEnv inject("CULLIDE_INJECT_GL_ERROR", "no check has this name");
    culler->run(asObjects(meshes), result);
    EXPECT_FALSE(result.stats.levels.empty()) << "the GPU levels must run for this test to mean anything";
    EXPECT_EQ(result.stats.gpuFallbacks, 0u);
}

TEST(ExactTriangles, OffGivesTheCandidatesASupersetWithoutExactTests) {
    // Settings::exactTriangles = false (the Bullet adapter's setting): the surviving candidate pairs, a superset
    // of the exact pairs, and no exact test run; object pairs may be more (candidates without an exact pair).
    for (GpuLevels levels : {GpuLevels::Never, GpuLevels::Always}) {
        Settings settings;
        settings.gpuLevels = levels;
        settings.exactThreshold = 0;
        settings.exactTriangles = false;
        settings.margin = 0.01;
        CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
        const auto meshes = randomSoups(21, 40, 100, 0.08);
        const auto objects = asObjects(meshes);
        Result reference, candidates;
        createReferenceCuller(settings)->run(objects, reference);
        culler->run(objects, candidates);
        const Comparison c = compare(reference, candidates);
        ASSERT_GT(c.expected, 0u);
        EXPECT_EQ(c.missed, 0u) << c.firstMissed;
        EXPECT_GT(c.spurious, 0u) << "candidates should include pairs whose boxes overlap but triangles do not";
        EXPECT_EQ(candidates.stats.exactTests, 0u);
        EXPECT_EQ(candidates.stats.intersectingTrianglePairs, 0u);
        std::size_t listed = 0;
        for (const ObjectPair& p : candidates.pairs) listed += p.triangles.size();
        EXPECT_EQ(listed, candidates.stats.candidateTrianglePairs);
    }
}

namespace fs = std::filesystem;

struct CliRun {
    int status = -1;
    std::string out;
    std::string err;
};

std::string readFile(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

/// Two crossing triangles (one intersecting pair) as OFF files and a scene file; returns the scene's path.
fs::path writeCrossingScene(const fs::path& dir) {
    fs::create_directories(dir);
    std::ofstream(dir / "a.off") << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::ofstream(dir / "b.off") << "OFF\n3 1 0\n0.2 0.2 -0.5\n0.2 0.2 0.5\n0.9 0.9 0\n3 0 1 2\n";
    std::ofstream(dir / "scene.json") << "{\"objects\": [{\"mesh\": \"a.off\"}, {\"mesh\": \"b.off\"}]}";
    return dir / "scene.json";
}

/// cullide-pairs with `env` prepended (VAR=value ...), its exit status, standard output and error.
CliRun runPairs(const fs::path& dir, const std::string& args, const std::string& env) {
    const std::string command = env + " " + CULLIDE_PAIRS_EXE + " " + args + " > " + (dir / "stdout").string() +
                                " 2> " + (dir / "stderr").string();
    const int raw = std::system(command.c_str());
    return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, readFile(dir / "stdout"), readFile(dir / "stderr")};
}

TEST(NoGlDevice, CullidePairsRunsTheCpuPathUnlessGpuLevelsAreDemanded) {
    const fs::path dir = fs::temp_directory_path() / ("cullide_no_gl_" + std::to_string(::getpid()));
    const std::string scene = writeCrossingScene(dir).string();
    // No EGL vendor library at all (libglvnd finds none), and a device preference that cannot exist.
    const std::string noGl = "__EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent.json CULLIDE_GL_DEVICE=99";
    for (const char* levels : {"never", "auto"}) {
        const CliRun r = runPairs(dir, scene + " --gpu-levels " + levels, noGl);
        ASSERT_EQ(r.status, 0) << levels << ": " << r.err;
        const auto doc = nlohmann::json::parse(r.out);
        EXPECT_EQ(doc["object_pairs"], nlohmann::json::parse("[[0, 1]]")) << r.out;
        EXPECT_EQ(doc["triangle_pairs"], nlohmann::json::parse("[[0, 0, 1, 0]]")) << r.out;
        EXPECT_EQ(doc["stats"]["device"], "none") << r.out;
        EXPECT_TRUE(doc["stats"].contains("gpu_unavailable")) << r.out;
        const bool notice = r.err.find("CPU path") != std::string::npos;
        EXPECT_EQ(notice, std::string(levels) == "auto") << levels << ": " << r.err;
    }
    for (const char* demanding : {"--gpu-levels always", "--pipeline paper"}) {
        const CliRun r = runPairs(dir, scene + " " + demanding, noGl);
        EXPECT_EQ(r.status, 3) << demanding << ": " << r.err;
    }
    const CliRun contradictory = runPairs(dir, scene + " --pipeline paper --gpu-levels never", "");
    EXPECT_EQ(contradictory.status, 2) << contradictory.err;
    EXPECT_NE(contradictory.err.find("Never"), std::string::npos) << contradictory.err;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace cullide::test
