// readMesh: the reader chosen by the file's extension, file errors, and the real meshes when fetched
// (scripts/fetch_meshes.sh).
#include "ReaderSupport.h"
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <string>

namespace cullide::io {
namespace {

using namespace cullide::test;

// ---------------------------------------------------------------------------------------------------------------
// Files

TEST(ReadMesh, ChoosesTheReaderByExtension) {
    TempDir dir;
    const std::string a = dir.write("cube.OFF", kCubeOff);
    const std::string b = dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_EQ(readMesh(a).triangles.size(), 12u);
    EXPECT_EQ(readMesh(b).triangles.size(), 1u);
    const std::string bad = dir.write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n");
    EXPECT_TRUE(throwsAt([&] { readMesh(bad); }, 5, bad));
    EXPECT_TRUE(throwsAt([&] { readMesh(dir.write("x.stl", "solid")); }, 0));
    EXPECT_TRUE(throwsAt([&] { readMesh((dir.path() / "missing.off").string()); }, 0));
    EXPECT_TRUE(throwsAt([&] { readMesh(dir.path().string() + "/sub.off/"); }, 0));
    fs::create_directories(dir.path() / "dir.off");
    EXPECT_TRUE(throwsAt([&] { readMesh((dir.path() / "dir.off").string()); }, 0));
}

TEST(ReadMesh, RealMeshesWhenFetched) {
    const fs::path dir = scenes::defaultDataDir();
    if (!fs::exists(dir / "bunny00.off")) GTEST_SKIP() << "run scripts/fetch_meshes.sh to test the real meshes";
    const TriangleMesh bunny = readMesh((dir / "bunny00.off").string());
    EXPECT_EQ(bunny.vertices.size(), 37706u);
    EXPECT_EQ(bunny.triangles.size(), 75408u);
    if (fs::exists(dir / "ChineseDragon-10kv.off")) {
        const TriangleMesh dragon = readMesh((dir / "ChineseDragon-10kv.off").string());
        EXPECT_EQ(dragon.vertices.size(), 10000u);
        EXPECT_EQ(dragon.triangles.size(), 19994u);
    }
}

}  // namespace
}  // namespace cullide::io
