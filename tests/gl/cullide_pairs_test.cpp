// cullide-pairs end to end: generated scenes against the in-process reference, malformed input, no GL.
#include "Compare.h"
#include "GlTestSupport.h"
#include "cullide/io/MeshIO.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
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

CliRun runPairs(const std::string& args, const std::string& env = "") {
    const fs::path dir = fs::temp_directory_path() / ("cullide_pairs_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string out = (dir / "stdout").string();
    const std::string err = (dir / "stderr").string();
    const std::string command = env + " " + CULLIDE_PAIRS_EXE + " " + args + " > " + out + " 2> " + err;
    const int raw = std::system(command.c_str());
    CliRun r;
    r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    std::ifstream o(out), e(err);
    std::stringstream so, se;
    so << o.rdbuf();
    se << e.rdbuf();
    r.out = so.str();
    r.err = se.str();
    return r;
}

/// Writes randomSoups meshes as OFF files plus scene.json (with non-trivial transforms) into a fresh directory.
fs::path writeScene(std::uint64_t seed) {
    const fs::path dir = fs::temp_directory_path() / ("cullide_scene_" + std::to_string(::getpid()) + "_" +
                                                      std::to_string(seed));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const auto meshes = randomSoups(seed, 8, 60, 0.25);
    std::string json = "{\"objects\": [";
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        const std::string name = "m" + std::to_string(i) + ".off";
        std::ofstream f(dir / name);
        io::writeOff(meshes[i], f);
        json += std::string(i ? "," : "") + "{\"mesh\": \"" + name + "\"" +
                (i % 2 ? ", \"transform\": [0, -1, 0, 0.5, 1, 0, 0, 0, 0, 0, 1, 0.125, 0, 0, 0, 1]" : "") + "}";
    }
    json += "]}";
    std::ofstream(dir / "scene.json") << json;
    return dir;
}

TEST(CullidePairs, MatchesTheReferenceOnGeneratedScenes) {
    {
        CULLIDE_GPU_CULLER_OR_SKIP(probe, Settings{});  // GL policy: skip outside CI only
    }
    for (std::uint64_t seed : {1u, 2u}) {
        const fs::path dir = writeScene(seed);
        const CliRun run = runPairs((dir / "scene.json").string() + " --resolution 64 --gpu-levels always");
        ASSERT_EQ(run.status, 0) << run.err;
        const auto j = nlohmann::json::parse(run.out);
        // The same scene through the library's reader and the brute-force reference.
        const auto scene = io::readSceneFile((dir / "scene.json").string());
        std::vector<TriangleMesh> meshes;
        for (const auto& o : scene) meshes.push_back(io::worldMesh(o));
        Result expected;
        createReferenceCuller(Settings{})->run(asObjects(meshes), expected);
        std::vector<std::array<std::uint32_t, 4>> want;
        for (const auto& p : trianglePairs(expected)) want.push_back(p);
        std::vector<std::array<std::uint32_t, 4>> got;
        for (const auto& t : j.at("triangle_pairs")) got.push_back({t[0].get<std::uint32_t>(), t[1].get<std::uint32_t>(), t[2].get<std::uint32_t>(), t[3].get<std::uint32_t>()});
        EXPECT_EQ(got, want) << "seed " << seed;  // every pair exactly once, sorted
        EXPECT_EQ(j.at("objects").get<std::size_t>(), meshes.size());
        EXPECT_FALSE(want.empty());
        for (const auto& p : j.at("object_pairs")) EXPECT_LT(p[0].get<int>(), p[1].get<int>());
        EXPECT_GT(j.at("stats").at("draws").get<int>(), 0);
    }
}

TEST(CullidePairs, MalformedInputExitsWithTwoAndNamesFileAndLine) {
    const fs::path dir = fs::temp_directory_path() / ("cullide_bad_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "bad.json") << "{\"objects\": [\n  {\"mesh\": \"x.off\",\n  oops}\n]}";
    CliRun r = runPairs((dir / "bad.json").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("bad.json:3"), std::string::npos) << r.err;

    std::ofstream(dir / "t.off") << "OFF\n3 1 0\n0 0 0\n1 0 nan\n0 1 0\n3 0 1 2\n";
    std::ofstream(dir / "nan.json") << "{\"objects\": [{\"mesh\": \"t.off\"}]}";
    r = runPairs((dir / "nan.json").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("t.off:4"), std::string::npos) << r.err;

    std::ofstream(dir / "missing.json") << "{\"objects\": [{\"mesh\": \"nope.off\"}]}";
    EXPECT_EQ(runPairs((dir / "missing.json").string()).status, 2);
    EXPECT_EQ(runPairs((dir / "missing.json").string() + " --resolution 3").status, 2);
    EXPECT_EQ(runPairs("--no-such-flag").status, 2);
    EXPECT_EQ(runPairs("").status, 2);
}

TEST(CullidePairs, HostileSceneInputGivesShortClearErrors) {
    const fs::path dir = fs::temp_directory_path() / ("cullide_hostile_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    // A NUL in a mesh path: refused at the scene's line, the NUL shown escaped (it used to open plain.txt).
    std::ofstream(dir / "plain.txt") << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::ofstream(dir / "nul.json") << "{\"objects\": [\n{\"mesh\": \"plain.txt\\u0000.off\"}]}";
    CliRun r = runPairs((dir / "nul.json").string());
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("nul.json:2: objects[0].mesh contains a NUL byte"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("plain.txt\\0.off"), std::string::npos) << r.err;
    // A 1 MB mesh name: a short message.
    std::ofstream(dir / "long.json") << "{\"objects\": [{\"mesh\": \"" << std::string(1000000, 'a') << ".off\"}]}";
    r = runPairs((dir / "long.json").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_LT(r.err.size(), 500u) << r.err.substr(0, 500);
    // A 20 MB single-line OFF: rejected at its counts line, without reading the line.
    {
        std::ofstream big(dir / "big.off");
        big << "OFF 3 1 0";
        for (int i = 0; i < 10000000; ++i) big << " 1";
        big << "\n";
    }
    std::ofstream(dir / "big.json") << "{\"objects\": [{\"mesh\": \"big.off\"}]}";
    r = runPairs((dir / "big.json").string());
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("big.off:1: too many values on the counts line"), std::string::npos) << r.err;
    fs::remove_all(dir);
}

TEST(CullidePairs, NoGlExitsWithThreeWhenGpuLevelsAreDemanded) {
    const fs::path dir = writeScene(3);
    const CliRun r = runPairs((dir / "scene.json").string() + " --gpu-levels always", "CULLIDE_GL_DEVICE=99");
    EXPECT_EQ(r.status, 3) << r.err;
    EXPECT_NE(r.err.find("99"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace cullide::test
