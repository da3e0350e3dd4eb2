// cullide-demo end to end on every scene (breakable, env1, env2, env3): it writes its CSV, summary and PNGs, and its
// checks against the exact reference miss nothing.
#include "DemoRun.h"

#include "cullide/io/Image.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace cullide::demo {
namespace {

namespace fs = std::filesystem;
using namespace cullide::test;

/// Fraction of pixels that differ from the top-left pixel (the background).
double nonBackground(const Image& image) {
    std::size_t differ = 0;
    const std::size_t n = std::size_t(image.width) * std::size_t(image.height);
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
            if (image.rgba[4 * i + c] != image.rgba[c]) {
                ++differ;
                break;
            }
    return n ? double(differ) / double(n) : 0.0;
}

struct SceneCase {
    const char* scene;
    int frames;
    int snapshotEvery;
};

class DemoScenes : public ::testing::TestWithParam<SceneCase> {};

TEST_P(DemoScenes, WritesCsvSummaryAndPngsAndMissesNothing) {
    const SceneCase c = GetParam();
    const fs::path out = freshDir(c.scene);
    const fs::path log = out / "log.txt";
    const std::string args = std::string("--scene ") + c.scene + " --frames " + std::to_string(c.frames) +
                             " --snapshot-every " + std::to_string(c.snapshotEvery) + " --check-every 4 --out " +
                             out.string() + (std::string(c.scene) == "env1" ? " --objects 40" : "");
    const int status = runDemo(args, log);
    SKIP_IF_NO_GL(status, log);
    ASSERT_EQ(status, 0) << slurp(log);

    // frames.csv: a header and one row per frame; the missed column is 0 on checked frames.
    std::ifstream csv(out / "frames.csv");
    std::string line;
    ASSERT_TRUE(std::getline(csv, line));
    EXPECT_EQ(line.rfind("frame,path,culled_pairs,pruned_pairs,objects,triangles,", 0), 0u) << line;
    int rows = 0;
    std::size_t firstObjects = 0, lastObjects = 0;
    while (std::getline(csv, line)) {
        std::vector<std::string> cells;
        std::stringstream s(line);
        for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
        if (line.back() == ',') cells.push_back("");
        ASSERT_EQ(cells.size(), 25u) << line;
        EXPECT_EQ(std::stoi(cells[0]), rows);
        // The environments run the culler every frame; the breakable scene's default (Culling::Auto) culls nothing
        // where it does not trial (no hardware GL device).
        if (std::string(c.scene) != "breakable") {
            EXPECT_TRUE(cells[1] == "cpu-path" || cells[1] == "gpu-levels") << line;
        }
        if (rows % 4 == 0) {
            EXPECT_EQ(cells[24], "0") << "frame " << rows << " missed pairs";
        } else {
            EXPECT_EQ(cells[24], "");
        }
        if (rows == 0) firstObjects = std::stoul(cells[4]);
        lastObjects = std::stoul(cells[4]);
        ++rows;
    }
    EXPECT_EQ(rows, c.frames);

    const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_EQ(summary["scene"], c.scene);
    EXPECT_EQ(summary["frames"], c.frames);
    // The culler's renderer: empty where it opened no GL context (Auto on a software renderer); the snapshots'.
    EXPECT_FALSE(summary["snapshot_renderer"].get<std::string>().empty());
    EXPECT_EQ(summary["check"]["missed"], 0);
    EXPECT_GT(summary["check"]["frames_checked"].get<int>(), 0);
    EXPECT_GT(summary["ms"]["frame"]["median"].get<double>(), 0.0);
    if (std::string(c.scene) == "breakable") {
        EXPECT_GT(summary["fractures"].get<int>(), 0) << "the breakable scene must fracture";
        EXPECT_GT(lastObjects, firstObjects) << "fracture must add bodies";
    }

    // Snapshots every K frames plus the last one, and a contact sheet; all decode to non-trivial images.
    const auto snapshots = summary["snapshots"];
    EXPECT_EQ(int(snapshots.size()), (c.frames - 1) / c.snapshotEvery + 1 + ((c.frames - 1) % c.snapshotEvery ? 1 : 0));
    for (const auto& name : snapshots) {
        const Image image = io::readPng((out / name.get<std::string>()).string());
        EXPECT_EQ(image.width, 640);
        EXPECT_EQ(image.height, 480);
        EXPECT_GT(nonBackground(image), 0.02) << name;
    }
    const Image sheet = io::readPng((out / "contact_sheet.png").string());
    EXPECT_GT(sheet.width, 320);
    EXPECT_GT(nonBackground(sheet), 0.02);
}

INSTANTIATE_TEST_SUITE_P(Scenes, DemoScenes,
                         ::testing::Values(SceneCase{"breakable", 28, 9}, SceneCase{"env1", 6, 5},
                                           SceneCase{"env2", 3, 2}, SceneCase{"env3", 3, 2}),
                         [](const auto& param) { return std::string(param.param.scene); });

}  // namespace
}  // namespace cullide::demo
