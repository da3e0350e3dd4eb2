// cullide-demo's command line: snapshots and checks do not change the simulation; bad flags and meshes give clear
// errors; frames.csv and summary.json say which path culled each frame.
#include "DemoRun.h"
#include "cullide/Culler.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace cullide::demo {
namespace {

namespace fs = std::filesystem;
using namespace cullide::test;

/// The physics columns of frames.csv (frame .. new_pieces, 16 of them), without the timings.
std::string physicsColumns(const fs::path& csv) {
    std::ifstream in(csv);
    std::string out, line;
    while (std::getline(in, line)) {
        std::size_t comma = 0;
        for (int k = 0; k < 16 && comma != std::string::npos; ++k) comma = line.find(',', comma + 1);
        out += line.substr(0, comma) + "\n";
    }
    return out;
}

TEST(DemoCli, SnapshotsAndChecksDoNotChangeTheSimulation) {
    // Snapshots and checks run extra cullers and GL between steps: the run must stay the same (this caught an
    // uninitialised impact point that made the fracture depend on the heap's history).
    const fs::path a = freshDir("det_a"), b = freshDir("det_b");
    const int status = runDemo("--frames 24 --snapshot-every 0 --out " + a.string(), a / "log.txt");
    SKIP_IF_NO_GL(status, a / "log.txt");
    ASSERT_EQ(status, 0) << slurp(a / "log.txt");
    ASSERT_EQ(runDemo("--frames 24 --snapshot-every 3 --check-every 2 --out " + b.string(), b / "log.txt"), 0)
        << slurp(b / "log.txt");
    EXPECT_EQ(physicsColumns(a / "frames.csv"), physicsColumns(b / "frames.csv"));
}

TEST(DemoCli, BadFlagsAndMeshesGiveClearErrors) {
    const fs::path out = freshDir("cli");
    const fs::path log = out / "log.txt";
    EXPECT_EQ(runDemo("--help", log), 0);
    EXPECT_NE(slurp(log).find("usage: cullide-demo"), std::string::npos);
    EXPECT_EQ(runDemo("--scene nosuch", log), 2);
    EXPECT_NE(slurp(log).find("--scene expects"), std::string::npos) << slurp(log);
    EXPECT_EQ(runDemo("--frames 0", log), 2);
    EXPECT_EQ(runDemo("--resolution 5", log), 2);
    EXPECT_EQ(runDemo("--mode fast", log), 2);
    EXPECT_EQ(runDemo("--bogus", log), 2);
    EXPECT_EQ(runDemo("--frames", log), 2);
    EXPECT_EQ(runDemo("--scene env1 --mesh x.off", log), 2) << "flags the scene would ignore are errors";
    EXPECT_EQ(runDemo("--scene breakable --objects 5", log), 2);
    EXPECT_EQ(runDemo("--pipeline fast", log), 2);
    EXPECT_EQ(runDemo("--deep-penetration-fallback maybe", log), 2);
    EXPECT_EQ(runDemo("--pipeline bullet-dbvt --deep-penetration-fallback off", log), 2);
    EXPECT_NE(slurp(log).find("applies to --scene breakable with --pipeline cullide only"), std::string::npos);
    EXPECT_EQ(runDemo("--culling maybe", log), 2);
    EXPECT_NE(slurp(log).find("--culling expects auto, on or off"), std::string::npos) << slurp(log);
    EXPECT_EQ(runDemo("--gimpact-pair-culling maybe", log), 2);
    EXPECT_EQ(runDemo("--scene env1 --culling on", log), 2);
    EXPECT_EQ(runDemo("--culling off --deep-penetration-fallback off", log), 2);
    EXPECT_NE(slurp(log).find("applies where pairs may be culled"), std::string::npos) << slurp(log);

    std::ofstream(out / "bad.off") << "OFF\n3 1 0\n0 0 0\n1 0 0\n";  // truncated
    const int status = runDemo("--mesh " + (out / "bad.off").string() + " --frames 1 --out " + out.string(), log);
    SKIP_IF_NO_GL(status, log);
    EXPECT_EQ(status, 4) << slurp(log);
    EXPECT_NE(slurp(log).find("bad.off"), std::string::npos) << slurp(log);
    EXPECT_EQ(runDemo("--mesh /nonexistent.obj --frames 1 --out " + out.string(), log), 4) << slurp(log);
    // A missing file is reported as missing, not by its (absent) extension.
    EXPECT_EQ(runDemo("--mesh /nonexistent --frames 1 --out " + out.string(), log), 4) << slurp(log);
    EXPECT_NE(slurp(log).find("/nonexistent: file does not exist"), std::string::npos) << slurp(log);
    EXPECT_EQ(slurp(log).find("unsupported"), std::string::npos) << slurp(log);
}

/// The rows of frames.csv as cells (header first).
std::vector<std::vector<std::string>> csvRows(const fs::path& csv) {
    std::ifstream in(csv);
    std::vector<std::vector<std::string>> rows;
    for (std::string line; std::getline(in, line);) {
        std::vector<std::string> cells;
        std::stringstream s(line);
        for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
        if (!line.empty() && line.back() == ',') cells.push_back("");
        rows.push_back(cells);
    }
    return rows;
}

TEST(DemoCli, SaysWhichPathCulledEachFrame) {
    // --culling on: the pieces' pairs go through the culler (its CPU path or its GPU levels): frames.csv names the
    // path and counts the culled pairs, summary.json sums them. --culling off: no frame is culled.
    const fs::path on = freshDir("culling_on"), off = freshDir("culling_off"), byDefault = freshDir("culling_auto");
    const int status = runDemo("--frames 24 --snapshot-every 0 --culling on --out " + on.string(), on / "log.txt");
    SKIP_IF_NO_GL(status, on / "log.txt");
    ASSERT_EQ(status, 0) << slurp(on / "log.txt");
    ASSERT_EQ(runDemo("--frames 24 --snapshot-every 0 --culling off --out " + off.string(), off / "log.txt"), 0);
    ASSERT_EQ(runDemo("--frames 24 --snapshot-every 0 --out " + byDefault.string(), byDefault / "log.txt"), 0);
    const auto rowsOn = csvRows(on / "frames.csv"), rowsOff = csvRows(off / "frames.csv");
    ASSERT_EQ(rowsOn.size(), 25u);
    ASSERT_EQ(rowsOn[0][1], "path");
    ASSERT_EQ(rowsOn[0][2], "culled_pairs");
    std::size_t culledFrames = 0, culledPairs = 0;
    for (std::size_t r = 1; r < rowsOn.size(); ++r) {
        const std::string& path = rowsOn[r][1];
        EXPECT_TRUE(path == "cpu-path" || path == "gpu-levels" || path == "not-culled") << path;
        culledFrames += path != "not-culled" ? 1 : 0;
        culledPairs += std::stoul(rowsOn[r][2]);
        if (path == "gpu-levels") {
            EXPECT_FALSE(rowsOn[r][8].empty()) << "the levels' set sizes";
        }
    }
    EXPECT_GT(culledFrames, 0u);
    EXPECT_GT(culledPairs, 0u);
    for (std::size_t r = 1; r < rowsOff.size(); ++r) {
        EXPECT_EQ(rowsOff[r][1], "not-culled") << r;
        EXPECT_EQ(rowsOff[r][2], "0") << r;
    }
    const auto summaryOn = nlohmann::json::parse(slurp(on / "summary.json"));
    EXPECT_EQ(summaryOn["culling"]["setting"], "on");
    EXPECT_EQ(summaryOn["culling"]["culled_pair_steps"].get<std::size_t>(), culledPairs);
    const auto summaryAuto = nlohmann::json::parse(slurp(byDefault / "summary.json"));
    EXPECT_EQ(summaryAuto["culling"]["setting"], "auto");
    if (!hasHardwareGlDevice()) {  // Auto does not trial here: nothing is culled, and the summary says why
        EXPECT_EQ(summaryAuto["culling"]["auto"]["state"], "not trialled");
        EXPECT_EQ(summaryAuto["culling"]["culled_pair_steps"], 0);
    }
}

}  // namespace
}  // namespace cullide::demo
