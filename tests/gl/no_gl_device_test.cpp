// No GL device at all (issue 13): cullide-pairs runs the CPU path unless GPU levels are demanded, and rejects the
// paper's pipeline without GPU levels.
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
        // Neither prints a notice: never opens no context by request, auto opens none where there is no hardware
        // device (it would not run GPU levels on any other).
        EXPECT_EQ(r.err.find("CPU path"), std::string::npos) << levels << ": " << r.err;
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
