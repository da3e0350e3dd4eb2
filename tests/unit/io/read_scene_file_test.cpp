// Scene files (readSceneFile): meshes loaded and transformed; errors that name the file and the line.
#include "ReaderSupport.h"

#include <gtest/gtest.h>

#include <string>

namespace cullide::io {
namespace {

using namespace cullide::test;

// ---------------------------------------------------------------------------------------------------------------
// Scene files

TEST(ReadSceneFile, LoadsAndTransformsMeshes) {
    TempDir dir;
    dir.write("meshes/tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    dir.write("meshes/quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    const std::string scene = dir.write("scene.json", R"({
  "objects": [
    {"mesh": "meshes/tri.off"},
    {"mesh": "meshes/quad.obj", "transform": [2, 0, 0, 10,
                                               0, 1, 0, 20,
                                               0, 0, 1, 30,
                                               0, 0, 0, 1]},
    {"mesh": "meshes/tri.off", "transform": [0, -1, 0, 0,  1, 0, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1], "extra": true}
  ]
})");
    const std::vector<SceneObject> s = readSceneFile(scene);
    ASSERT_EQ(s.size(), 3u);
    EXPECT_EQ(s[0].meshPath, "meshes/tri.off");
    EXPECT_EQ(s[0].transform, Eigen::Matrix4d::Identity());
    EXPECT_EQ(worldMesh(s[0]).vertices[1], Vec3(1, 0, 0));
    ASSERT_EQ(s[1].mesh->triangles.size(), 2u);
    EXPECT_EQ(s[0].mesh, s[2].mesh);  // one file, read once, shared
    EXPECT_EQ(s[1].transform(0, 3), 10.0);
    EXPECT_EQ(worldMesh(s[1]).vertices[2], Vec3(12, 21, 30));
    // Rotation by 90 degrees about z: (1, 0, 0) -> (0, 1, 0).
    EXPECT_EQ(worldMesh(s[2]).vertices[1], Vec3(0, 1, 0));
    EXPECT_EQ(worldMesh(s[2]).vertices[2], Vec3(-1, 0, 0));

    // An empty scene is valid; an absolute mesh path is used as is.
    EXPECT_TRUE(readSceneFile(dir.write("empty.json", R"({"objects": []})")).empty());
    const std::string abs = (dir.path() / "meshes" / "tri.off").string();
    EXPECT_EQ(readSceneFile(dir.write("sub/abs.json", "{\"objects\": [{\"mesh\": \"" + abs + "\"}]}")).size(), 1u);
}

TEST(ReadSceneFile, ErrorsNameTheFileAndLine) {
    TempDir dir;
    dir.write("tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const std::string broken = dir.write("broken.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n");
    auto scene = [&](const std::string& text) { return dir.write("s.json", text); };
    auto failsAt = [&](const std::string& text, std::size_t line) {
        const std::string path = scene(text);
        return throwsAt([&] { readSceneFile(path); }, line, path);
    };

    EXPECT_TRUE(throwsAt([&] { readSceneFile((dir.path() / "none.json").string()); }, 0));
    EXPECT_TRUE(failsAt("", 1));
    EXPECT_TRUE(failsAt("{\n  \"objects\": [\n    {\"mesh\": \"tri.off\",,}\n  ]\n}\n", 3));
    EXPECT_TRUE(failsAt("{\n  \"objects\": [\n    {\"mesh\": \"tri.off\"}\n", 4));  // truncated
    EXPECT_TRUE(failsAt("{\"objects\": []} trailing", 1));
    EXPECT_TRUE(failsAt("\n[1, 2]\n", 2));
    EXPECT_TRUE(failsAt("{\n\"other\": 1\n}\n", 1));
    EXPECT_TRUE(failsAt("{\n\"objects\":\n {}\n}\n", 3));
    EXPECT_TRUE(failsAt("{\"objects\": [\n{\"mesh\": \"tri.off\"},\n 7\n]}\n", 3));
    EXPECT_TRUE(failsAt("{\"objects\": [\n{\"mesh\": \"tri.off\"},\n {\"transform\": []}\n]}\n", 3));
    EXPECT_TRUE(failsAt("{\"objects\": [\n{\n\"mesh\":\n 5}]}\n", 4));
    EXPECT_TRUE(failsAt("{\"objects\": [\n{\n\"mesh\": \"\"}]}\n", 3));
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\",\n\"transform\": [1, 0, 0, 0]}]}\n", 2));
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\",\n\"transform\": \"identity\"}]}\n", 2));
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\", \"transform\": [1, 0, 0, 0,\n 0, 1, 0, 0,\n"
                        " 0, \"0\", 1, 0,\n 0, 0, 0, 1]}]}\n",
                        3));
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\", \"transform\": [1, 0, 0, 0,\n 0, 1, 0, 0,\n"
                        " 0, null, 1, 0,\n 0, 0, 0, 1]}]}\n",
                        3));
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\", \"transform\": [1, 0, 0, 0,\n 0, 1, 0, 0,\n"
                        " 0, 0, 1, 0,\n 0, 0, 1e999, 1]}]}\n",
                        4));
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\",\n \"transform\": [1, 0, 0, 0, 0, 1, 0, 0,"
                        " 0, 0, 1, 0, 0, 0, 2, 1]}]}\n",
                        2));  // not affine
    EXPECT_TRUE(failsAt("{\"objects\": [{\"mesh\": \"tri.off\",\n \"transform\": [1e300, 0, 0, 0, 0, 1, 0, 0,"
                        " 0, 0, 1, 0, 0, 0, 0, 1]},\n{\"mesh\": \"tri.off\",\n \"transform\": [1.5e308, 0, 0, 1.5e308,"
                        " 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}]}\n",
                        4));  // the second overflows to infinity
    EXPECT_TRUE(failsAt("{\"objects\": [\n{\"mesh\": \"tri.off\"},\n{\"mesh\":\n \"missing.off\"}]}\n", 4));
    EXPECT_TRUE(failsAt(std::string("{\"objects\": [\n\x01\x02\x03]}", 18), 2));
    EXPECT_TRUE(failsAt("{\"objects\": [\n{\"mesh\": \"bad\xff\"}]}\n", 2));  // invalid UTF-8
    EXPECT_TRUE(failsAt("{\"objects\": [\n  {\"mesh\": \"tri.off\"}, // comment\n]}\n", 2));
    // Errors inside a mesh name the mesh file and its line.
    const std::string path = scene("{\"objects\": [{\"mesh\": \"broken.off\"}]}");
    EXPECT_TRUE(throwsAt([&] { readSceneFile(path); }, 5, broken));
    // Keys spelled with escapes still locate the right line.
    EXPECT_TRUE(failsAt("{\"objects\": [{\"m\\u0065sh\": \"tri.off\",\n \"transform\": 1}]}\n", 2));
    // Deep nesting is rejected or handled, never a crash.
    EXPECT_THROW(readSceneFile(scene("{\"objects\": " + std::string(100000, '[') + std::string(100000, ']') + "}")),
                 ParseError);
}

}  // namespace
}  // namespace cullide::io
