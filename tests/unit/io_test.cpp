// Mesh and scene readers: good files, every kind of malformed input (ParseError with the right line) and a seeded
// garbage fuzz loop.
#include "cullide/io/MeshIO.h"
#include "cullide/scenes/Environments.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <streambuf>
#include <string>
#include <vector>

namespace cullide::io {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------------------------
// Helpers

/// A fresh temporary directory per test, removed afterwards.
class TempDir {
public:
    TempDir() {
        static int counter = 0;
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        m_path = fs::temp_directory_path() /
                 ("cullide_io_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" +
                  (info != nullptr ? std::string(info->name()) : std::string("x")));
        fs::remove_all(m_path);
        fs::create_directories(m_path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    std::string write(const std::string& name, const std::string& content) const {
        const fs::path p = m_path / name;
        fs::create_directories(p.parent_path());
        std::ofstream out(p, std::ios::binary);
        out << content;
        return p.string();
    }
    const fs::path& path() const { return m_path; }

private:
    fs::path m_path;
};

TriangleMesh off(const std::string& text) {
    std::istringstream in(text);
    return readOff(in, "test.off");
}

TriangleMesh obj(const std::string& text) {
    std::istringstream in(text);
    return readObj(in, "test.obj");
}

/// Runs `f`, expects a ParseError at `line` naming `file`; returns its message for further checks.
::testing::AssertionResult throwsAt(const std::function<void()>& f, std::size_t line,
                                    const std::string& file = "") {
    try {
        f();
    } catch (const ParseError& e) {
        if (e.line() != line) {
            return ::testing::AssertionFailure() << "ParseError at line " << e.line() << ", expected " << line
                                                 << ": " << e.what();
        }
        if (!file.empty() && e.file() != file) {
            return ::testing::AssertionFailure() << "ParseError names file '" << e.file() << "', expected '"
                                                 << file << "': " << e.what();
        }
        return ::testing::AssertionSuccess() << e.what();
    } catch (const std::exception& e) {
        return ::testing::AssertionFailure() << "threw a non-ParseError: " << e.what();
    }
    return ::testing::AssertionFailure() << "did not throw";
}

::testing::AssertionResult offFailsAt(const std::string& text, std::size_t line) {
    return throwsAt([&] { off(text); }, line, "test.off");
}

::testing::AssertionResult objFailsAt(const std::string& text, std::size_t line) {
    return throwsAt([&] { obj(text); }, line, "test.obj");
}

std::string messageOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const ParseError& e) {
        return e.what();
    }
    return "";
}

/// A stream that cannot seek (like a pipe): the reader cannot learn its size in advance.
class NonSeekableBuf : public std::streambuf {
public:
    explicit NonSeekableBuf(std::string s) : m_s(std::move(s)) { setg(m_s.data(), m_s.data(), m_s.data() + m_s.size()); }

private:
    std::string m_s;
};

const std::string kCubeOff =
    "OFF\n"
    "# a unit cube with quad faces\n"
    "8 6 12\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
    "0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3\n";

// ---------------------------------------------------------------------------------------------------------------
// OFF: good files

TEST(ReadOff, ReadsTrianglesExactly) {
    const TriangleMesh m = off("OFF\n4 2 0\n0 0 0\n1.5 -2 3e-3\n-0.25 1e2 7\n+1 .5 5.\n3 0 1 2\n3 2 1 3\n");
    ASSERT_EQ(m.vertices.size(), 4u);
    ASSERT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.vertices[1], Vec3(1.5, -2, 3e-3));
    EXPECT_EQ(m.vertices[2], Vec3(-0.25, 100, 7));
    EXPECT_EQ(m.vertices[3], Vec3(1, 0.5, 5));
    EXPECT_EQ(m.triangles[0], (TriangleIndices{0, 1, 2}));
    EXPECT_EQ(m.triangles[1], (TriangleIndices{2, 1, 3}));
}

TEST(ReadOff, FansPolygonsInFileOrder) {
    const TriangleMesh m = off("OFF\n6 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 2 0\n1 2 0\n"
                               "3 0 1 2\n4 0 1 2 3\n5 5 4 3 2 1\n");
    ASSERT_EQ(m.triangles.size(), 1u + 2u + 3u);
    const std::vector<TriangleIndices> expected = {{0, 1, 2}, {0, 1, 2}, {0, 2, 3}, {5, 4, 3}, {5, 3, 2}, {5, 2, 1}};
    EXPECT_EQ(m.triangles, expected);
}

TEST(ReadOff, CommentsBlankLinesHeaderVariantsAndColours) {
    // Counts on the header line, comments everywhere, CRLF, a BOM, tabs, face colours, vertex colours.
    const TriangleMesh a = off("\xEF\xBB\xBFOFF 3 1 0 # counts on the header line\r\n"
                               "\r\n# comment\n\t0 0 0   # first\n1 0 0\n\n0 1 0\n3 0 1 2 255 0 0 # red\n# end\n");
    ASSERT_EQ(a.vertices.size(), 3u);
    ASSERT_EQ(a.triangles.size(), 1u);
    EXPECT_EQ(a.vertices[2], Vec3(0, 1, 0));

    const TriangleMesh noHeader = off("# no header at all\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(noHeader.triangles.size(), 1u);

    const TriangleMesh coff = off("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n");
    EXPECT_EQ(coff.vertices[1], Vec3(1, 0, 0));

    const TriangleMesh cube = off(kCubeOff);
    EXPECT_EQ(cube.vertices.size(), 8u);
    EXPECT_EQ(cube.triangles.size(), 12u);

    const TriangleMesh empty = off("OFF\n0 0 0\n");
    EXPECT_TRUE(empty.vertices.empty());
    EXPECT_TRUE(empty.triangles.empty());

    // Degenerate faces (repeated indices) are valid triangle-soup input.
    EXPECT_EQ(off("OFF\n2 1 0\n0 0 0\n1 1 1\n3 0 0 1\n").triangles.size(), 1u);
}

TEST(ReadOff, TinyNumbersUnderflowInsteadOfFailing) {
    const TriangleMesh m = off("OFF\n3 1 0\n1e-400 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(m.vertices[0].x(), 0.0);
}

// ---------------------------------------------------------------------------------------------------------------
// OFF: malformed input

TEST(ReadOff, MissingOrBadCounts) {
    EXPECT_TRUE(offFailsAt("", 1));
    EXPECT_TRUE(offFailsAt("# only a comment\n\n", 3));
    EXPECT_TRUE(offFailsAt("OFF\n", 2));
    EXPECT_TRUE(offFailsAt("OFF\n# comment\n3\n", 3));
    EXPECT_TRUE(offFailsAt("OFF\nabc 1 0\n", 2));
    EXPECT_TRUE(offFailsAt("OFF\n3 x 0\n", 2));
    EXPECT_TRUE(offFailsAt("OFF\n-3 1 0\n", 2));
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0 7\n", 2));
    EXPECT_TRUE(offFailsAt("OFF\n3.5 1 0\n", 2));
    EXPECT_TRUE(offFailsAt("OFF\n99999999999999999999999 1 0\n", 2));
    EXPECT_TRUE(offFailsAt("hello world\n", 1));
    EXPECT_TRUE(offFailsAt("4OFF\n3 1 0\n", 1));
}

TEST(ReadOff, AbsurdCountsFailWithoutHugeAllocations) {
    // More vertices than 32-bit indices can address.
    EXPECT_TRUE(offFailsAt("OFF\n1000000000000 1 0\n0 0 0\n", 2));
    // Addressable but absurd: the file ends long before; nothing of that size may be reserved.
    EXPECT_TRUE(offFailsAt("OFF\n4000000000 1 0\n0 0 0\n", 4));
    EXPECT_TRUE(offFailsAt("OFF\n3 1000000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 7));
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000000000 0 1 2\n", 6));
    // Same through a stream whose size is unknown.
    NonSeekableBuf buf("OFF\n4000000000 4000000000 0\n0 0 0\n1 0 0\n");
    std::istream in(&buf);
    EXPECT_TRUE(throwsAt([&] { readOff(in, "pipe"); }, 5, "pipe"));
}

TEST(ReadOff, TruncatedFiles) {
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n0 0 0\n1 0 0\n", 5));
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n", 6));
    EXPECT_TRUE(offFailsAt("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2", 7));  // no final newline
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1", 5));
}

TEST(ReadOff, BadVertices) {
    const std::string head = "OFF\n3 1 0\n0 0 0\n";
    const std::string tail = "0 1 0\n3 0 1 2\n";
    for (const char* bad : {"1 0 x", "1 0", "1 0 nan", "1 0 NaN", "1 inf 0", "-inf 0 0", "1e999 0 0",
                            "1.2.3 0 0", "1 0 0x10", "1 0 --1", "1,0 0 0", "1 0 0 junk"}) {
        SCOPED_TRACE(bad);
        EXPECT_TRUE(offFailsAt(head + bad + "\n" + tail, 4));
    }
}

TEST(ReadOff, BadFaces) {
    const std::string head = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
    for (const char* bad : {"3 0 1 3", "3 0 1 -1", "2 0 1", "0", "-3 0 1 2", "5 0 1 2", "3 0 1 x", "3 0 1 2.0",
                            "3 0 1 99999999999999999999", "3 0 1 2 red", "x 0 1 2", "3 0 1 4294967296"}) {
        SCOPED_TRACE(bad);
        EXPECT_TRUE(offFailsAt(head + bad + "\n", 6));
    }
    const std::string msg = messageOf([&] { off(head + "3 0 1 3\n"); });
    EXPECT_NE(msg.find("test.off:6:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("out of range"), std::string::npos) << msg;
}

TEST(ReadOff, TrailingDataAndBinaryGarbage) {
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", 7));
    EXPECT_TRUE(offFailsAt(std::string("OFF\n3 1 0\n\x01\x02\x03\x7f\n", 14), 3));
    EXPECT_TRUE(offFailsAt(std::string("OFF\n3 1 0\n0 0 0\0\n1 0 0\n0 1 0\n3 0 1 2\n", 37), 3));
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n\xff\xfe\xfd 0 0\n", 3));
    std::string garbage;
    std::mt19937_64 gen(7);
    for (int i = 0; i < 4096; ++i) garbage += static_cast<char>(gen() & 0xff);
    EXPECT_THROW(off(garbage), ParseError);
    EXPECT_THROW(off("OFF\n" + garbage), ParseError);
}

// ---------------------------------------------------------------------------------------------------------------
// OBJ

TEST(ReadObj, ReadsAllFaceVariantsAndIgnoresOtherRecords) {
    const TriangleMesh m = obj(
        "# comment\n"
        "mtllib a.mtl\no thing\ng group\ns off\nusemtl red\n"
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\n"  // optional w
        "v 0 0 1 0.5 0.5 0.5\n"                      // vertex colour
        "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvp 0.5\n"
        "f 1 2 3\n"
        "f 1/1 2/2 3/3\n"
        "f 1//1 2//1 3//1\n"
        "f 1/1/1 2/2/1 3/3/1\n"
        "f -5 -4 -3\n"                                // relative: vertices 1 2 3
        "f 1 2 3 4\n"                                 // quad: fanned
        "l 1 2\n"
        "f\t1/1/1\t2/2/1   5/3/1  # tabs and a comment\r\n");
    ASSERT_EQ(m.vertices.size(), 5u);
    EXPECT_EQ(m.vertices[3], Vec3(0, 1, 0));
    EXPECT_EQ(m.vertices[4], Vec3(0, 0, 1));
    const std::vector<TriangleIndices> expected = {{0, 1, 2}, {0, 1, 2}, {0, 1, 2}, {0, 1, 2},
                                                   {0, 1, 2}, {0, 1, 2}, {0, 2, 3}, {0, 1, 4}};
    EXPECT_EQ(m.triangles, expected);
}

TEST(ReadObj, NegativeIndicesAreRelativeToTheVerticesReadSoFar) {
    const TriangleMesh m = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -1 -2 -3\n");
    const std::vector<TriangleIndices> expected = {{0, 1, 2}, {3, 2, 1}};
    EXPECT_EQ(m.triangles, expected);
}

TEST(ReadObj, ForwardReferencesAreResolvedAtTheEnd) {
    const TriangleMesh m = obj("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    EXPECT_EQ(m.triangles.size(), 1u);
    EXPECT_TRUE(objFailsAt("v 0 0 0\nf 1 2 3\nf 1 2 4\nv 1 0 0\nv 0 1 0\n", 3));
}

TEST(ReadObj, MalformedRecords) {
    const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    EXPECT_TRUE(objFailsAt("v 1 2\n", 1));
    EXPECT_TRUE(objFailsAt("v 1 2 x\n", 1));
    EXPECT_TRUE(objFailsAt("v nan 0 0\n", 1));
    EXPECT_TRUE(objFailsAt("v 0 0 0\nv 0 inf 0\n", 2));
    EXPECT_TRUE(objFailsAt("v 0 0 0\nv 0 1e400 0\n", 2));
    EXPECT_TRUE(objFailsAt(v3 + "f 1 2\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1 2 4\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 0 1 2\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f -4 -1 -2\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1 2 x\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1 2 3.0\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1/x/1 2 3\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1/1/1/1 2 3\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f /1 2 3\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1 2 99999999999999999999\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "f 1 2 4294967297\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + "%%% 1 2\n", 4));
    EXPECT_TRUE(objFailsAt(v3 + std::string("f 1 2 3\x01\n"), 4));
    EXPECT_TRUE(objFailsAt(std::string("v 0 0 0\n\0\0\0\0", 12), 2));
    EXPECT_TRUE(objFailsAt(v3 + "\n\n# ok\n\xc3\xa9t\xc3\xa9 1 2\n", 7));  // not a keyword
}

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

TEST(WriteOff, RoundTripsExactly) {
    TriangleMesh m;
    std::mt19937_64 gen(3);
    for (int i = 0; i < 200; ++i) {
        const double scale = std::ldexp(1.0, static_cast<int>(gen() % 200) - 100);
        m.vertices.emplace_back((static_cast<double>(gen() >> 11) * 0x1p-53 - 0.5) * scale, -0.0,
                                i == 0 ? 5e-324 : 1.0 / (i + 1));
    }
    for (std::uint32_t i = 0; i + 2 < 200; ++i) m.triangles.push_back({i, i + 1, i + 2});
    std::ostringstream out;
    writeOff(m, out);
    const TriangleMesh back = off(out.str());
    ASSERT_EQ(back.vertices.size(), m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) EXPECT_EQ(back.vertices[i], m.vertices[i]) << i;
    EXPECT_EQ(back.triangles, m.triangles);
    // Empty mesh.
    std::ostringstream e;
    writeOff(TriangleMesh{}, e);
    EXPECT_TRUE(off(e.str()).vertices.empty());
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

// ---------------------------------------------------------------------------------------------------------------
// Hostile input (issue 14): bounded time, memory and messages; messages that say what is wrong.

/// A non-seekable stream of `prefix` and then `pattern` repeated up to `limit` bytes in all; counts what it serves.
class PatternBuf : public std::streambuf {
public:
    PatternBuf(std::string prefix, std::string pattern, std::size_t limit)
        : m_prefix(std::move(prefix)), m_pattern(std::move(pattern)), m_limit(limit) {
        while (m_pattern.size() < 4096) m_pattern += m_pattern;  // whole repetitions: the same byte sequence
    }
    std::size_t served() const { return m_served; }

protected:
    int_type underflow() override {
        if (m_served >= m_limit) return traits_type::eof();
        m_chunk.clear();
        while (m_chunk.size() < (1 << 16) && m_served + m_chunk.size() < m_limit) {
            const std::size_t at = m_served + m_chunk.size();
            const std::size_t left = m_limit - at;
            if (at < m_prefix.size()) {
                m_chunk.append(m_prefix, at, std::min(left, m_prefix.size() - at));
            } else {
                const std::size_t from = (at - m_prefix.size()) % m_pattern.size();
                m_chunk.append(m_pattern, from, std::min(left, m_pattern.size() - from));
            }
        }
        m_served += m_chunk.size();
        setg(m_chunk.data(), m_chunk.data(), m_chunk.data() + m_chunk.size());
        return traits_type::to_int_type(m_chunk[0]);
    }

private:
    std::string m_prefix, m_pattern, m_chunk;
    std::size_t m_limit;
    std::size_t m_served = 0;
};

TEST(HostileInput, LongLinesAreRejectedWithoutReadingThemWhole) {
    // 64 MiB on one line; each reader must stop at the first bad token, having read one 64 KiB chunk or so.
    constexpr std::size_t kLimit = std::size_t(64) << 20;
    struct Case {
        const char* prefix;
        const char* pattern;
        bool off;
        const char* expect;
    };
    for (const Case& c : {Case{"OFF 3 1 0 ", "1 ", true, "too many values on the counts line"},
                          Case{"OFF\n3 1 0\n0 0 0 ", "x ", true, "unexpected token"},
                          Case{"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 ", "x ", true, "unexpected token"},
                          Case{"OFF\n", "7", true, "token longer than"},  // one endless token
                          Case{"v 0 0 0\nf 1 1 1 ", "x ", false, "invalid vertex index"},
                          Case{"v 1 2 3 ", "9", false, "token longer than"}}) {
        SCOPED_TRACE(c.prefix);
        PatternBuf buf(c.prefix, c.pattern, kLimit);
        std::istream in(&buf);
        const std::string msg = messageOf([&] { c.off ? readOff(in, "long") : readObj(in, "long"); });
        EXPECT_NE(msg.find(c.expect), std::string::npos) << msg;
        EXPECT_LE(buf.served(), std::size_t(1) << 20) << "the reader read on after the error";
        EXPECT_LT(msg.size(), 300u) << msg;
    }
    // Vertex colours make an arbitrarily long but valid vertex line: read through in O(1) memory, then the file
    // goes on as usual.
    std::string longVertex = "OFF\n3 1 0\n0 0 0";
    for (int i = 0; i < 200000; ++i) longVertex += " 1";
    const TriangleMesh m = off(longVertex + "\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(m.triangles.size(), 1u);
    // A valid polygon on a long line (100000 vertices) is read.
    std::string polygon = "OFF\n100000 1 0\n";
    for (int i = 0; i < 100000; ++i) polygon += "0 0 " + std::to_string(i) + "\n";
    polygon += "100000";
    for (int i = 0; i < 100000; ++i) polygon += " " + std::to_string(i);
    EXPECT_EQ(off(polygon + "\n").triangles.size(), 99998u);
}

TEST(HostileInput, MessagesAreBoundedAndEscapeControlBytes) {
    // A 1 MB name with a NUL and a newline in it: shortened, escaped; file() keeps the full name.
    const std::string name = std::string("a\0b\nc", 5) + std::string(1000000, 'n');
    try {
        std::istringstream in("OFF\n3 1 0\n0 0 x\n");
        readOff(in, name);
        FAIL() << "did not throw";
    } catch (const ParseError& e) {
        const std::string msg = e.what();
        EXPECT_LT(msg.size(), 400u);
        EXPECT_EQ(msg.rfind("a\\0b\\nc", 0), 0u) << msg;
        EXPECT_NE(msg.find("... (1000005 bytes):3: invalid vertex coordinate 'x'"), std::string::npos) << msg;
        EXPECT_EQ(e.file(), name);
    }
    // A scene naming a 1 MB mesh path: the error is at the scene's line and short.
    TempDir dir;
    const std::string scene =
        dir.write("long.json", "{\"objects\": [\n{\"mesh\": \"" + std::string(1000000, 'x') + ".off\"}]}\n");
    EXPECT_TRUE(throwsAt([&] { readSceneFile(scene); }, 2, scene));
    const std::string msg = messageOf([&] { readSceneFile(scene); });
    EXPECT_LT(msg.size(), 600u);
    EXPECT_NE(msg.find("1000004 bytes long"), std::string::npos) << msg.substr(0, 600);
    // Just under the path limit: the system's reason, still a short message.
    const std::string name255 = dir.write("long2.json", "{\"objects\": [{\"mesh\": \"" + std::string(300, 'y') + ".off\"}]}");
    const std::string msg2 = messageOf([&] { readSceneFile(name255); });
    EXPECT_NE(msg2.find("cannot resolve the path: File name too long"), std::string::npos) << msg2;
    EXPECT_LT(msg2.size(), 600u);
}

TEST(HostileInput, NulInAMeshPathIsRejectedAtTheSceneLine) {
    TempDir dir;
    // "plain.txt\u0000.off" used to pass the extension check and open plain.txt.
    dir.write("plain.txt", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const std::string scene = dir.write("nul.json", "{\"objects\": [\n  {\"mesh\": \"plain.txt\\u0000.off\"}\n]}\n");
    EXPECT_TRUE(throwsAt([&] { readSceneFile(scene); }, 2, scene));
    const std::string msg = messageOf([&] { readSceneFile(scene); });
    EXPECT_NE(msg.find("NUL"), std::string::npos) << msg;
    EXPECT_NE(msg.find("plain.txt\\0.off"), std::string::npos) << msg;  // the whole name, the NUL escaped
    // readMesh itself refuses such a path (a library caller can build one too).
    const std::string path = (dir.path() / "plain.txt").string() + std::string("\0.off", 5);
    EXPECT_TRUE(throwsAt([&] { readMesh(path); }, 0));
    EXPECT_NE(messageOf([&] { readMesh(path); }).find("NUL"), std::string::npos);
}

TEST(HostileInput, PathErrorsSayWhatIsWrong) {
    TempDir dir;
    // A symbolic-link loop is not a missing file: the system's reason is given.
    fs::create_symlink(dir.path() / "loop2.off", dir.path() / "loop1.off");
    fs::create_symlink(dir.path() / "loop1.off", dir.path() / "loop2.off");
    const std::string loop = (dir.path() / "loop1.off").string();
    std::string msg = messageOf([&] { readMesh(loop); });
    EXPECT_NE(msg.find("cannot resolve the path: Too many levels of symbolic links"), std::string::npos) << msg;
    const std::string scene = dir.write("loop.json", "{\"objects\": [\n{\"mesh\": \"loop1.off\"}]}");
    EXPECT_TRUE(throwsAt([&] { readSceneFile(scene); }, 2, scene));
    msg = messageOf([&] { readSceneFile(scene); });
    EXPECT_NE(msg.find("objects[0].mesh: cannot resolve the path: Too many levels of symbolic links"),
              std::string::npos)
        << msg;
    // A dangling link, a missing file without an extension (was "unsupported mesh format ''"), a directory.
    fs::create_symlink(dir.path() / "gone.off", dir.path() / "dangling.off");
    EXPECT_NE(messageOf([&] { readMesh((dir.path() / "dangling.off").string()); }).find("dangling symbolic link"),
              std::string::npos);
    msg = messageOf([&] { readMesh("/nonexistent"); });
    EXPECT_EQ(msg, "/nonexistent: file does not exist");
    EXPECT_NE(messageOf([&] { readMesh(dir.path().string()); }).find("a directory, not a file"), std::string::npos);
    // An existing file of another format still gets the format message.
    EXPECT_NE(messageOf([&] { readMesh(dir.write("m.stl", "solid")); }).find("unsupported mesh format '.stl'"),
              std::string::npos);
}

TEST(HostileInput, WrongOffCountsAreNamedAsSuch) {
    const std::string verts = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";  // lines 3-6
    // The header claims 10 vertices; the file has 4, then 2 faces (lines 7, 8) that get read as vertices.
    std::string msg;
    EXPECT_TRUE(offFailsAt("OFF\n10 2 0\n" + verts + "3 0 1 2\n3 1 2 3\n", 2));
    msg = messageOf([&] { off("OFF\n10 2 0\n" + verts + "3 0 1 2\n3 1 2 3\n"); });
    EXPECT_NE(msg.find("the file ends after 6 of the 10 declared vertices; line 7 looks like a face, not a vertex: "
                       "the vertex count 10 on line 2 is probably too large (the file has 4 vertex lines before it)"),
              std::string::npos)
        << msg;
    // Overstated by less than the faces: the faces run out instead; the message still points at the vertex count.
    msg = messageOf([&] { off("OFF\n5 2 0\n" + verts + "3 0 1 2 255 0 0\n3 1 2 3\n"); });
    EXPECT_NE(msg.find("expected 2 faces (counts on line 2), found 1; line 7 looks like a face"), std::string::npos)
        << msg;
    // Truly truncated: no face-like line, the plain count.
    msg = messageOf([&] { off("OFF\n10 2 0\n" + verts); });
    EXPECT_NE(msg.find("expected 10 vertices and 2 faces (counts on line 2), found 4 vertices"), std::string::npos)
        << msg;
    // Understated: the 4th vertex is read as the first face.
    EXPECT_TRUE(offFailsAt("OFF\n3 1 0\n" + verts + "3 0 1 2\n", 6));
    msg = messageOf([&] { off("OFF\n3 1 0\n" + verts + "3 0 1 2\n"); });
    EXPECT_NE(msg.find("if it is a vertex, the vertex count 3 on line 2 is too small"), std::string::npos) << msg;
    // Only the first face gets that hint.
    msg = messageOf([&] { off("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1\n"); });
    EXPECT_EQ(msg.find("too small"), std::string::npos) << msg;
}

/// A vertex whose first coordinate is the largest 64-bit integer: the face-likeness test (is the line "n i1 ... in"?)
/// compared n + 4 with the token count, an overflow (found by the readers' fuzzer; UBSan aborts on it).
TEST(HostileInput, AVertexOfHugeIntegersIsAVertex) {
    const TriangleMesh m = off("OFF\n3 1 0\n9223372036854775807 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    ASSERT_EQ(m.vertices.size(), 3u);
    EXPECT_EQ(m.vertices[0][0], 9223372036854775807.0);
    EXPECT_EQ(m.triangles.size(), 1u);
}

TEST(HostileInput, SceneFromAStream) {
    TempDir dir;
    dir.write("m/tri.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    std::istringstream in("{\"objects\": [{\"mesh\": \"tri.off\", \"transform\": [1,0,0,1, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]}");
    const std::vector<SceneObject> s = readScene(in, "inline scene", dir.path() / "m");
    ASSERT_EQ(s.size(), 1u);
    EXPECT_EQ(worldMesh(s[0]).vertices[1], Vec3(2, 0, 0));
    std::istringstream bad("{\"objects\": [\n{\"mesh\": \"none.off\"}]}");
    EXPECT_TRUE(throwsAt([&] { readScene(bad, "inline scene", dir.path()); }, 2, "inline scene"));
    // Larger than kMaxSceneFileBytes: refused while reading, before any parsing.
    PatternBuf huge("{\"objects\": [", " ", kMaxSceneFileBytes + 2);
    std::istream hugeIn(&huge);
    const std::string msg = messageOf([&] { readScene(hugeIn, "huge", dir.path()); });
    EXPECT_NE(msg.find("the scene is larger than 64 MiB"), std::string::npos) << msg;
}

// ---------------------------------------------------------------------------------------------------------------
// Fuzzing: mutated files must parse or throw ParseError, nothing else.

class Mutator {
public:
    explicit Mutator(std::uint64_t seed) : m_gen(seed) {}

    std::string mutate(std::string s) {
        const int rounds = 1 + static_cast<int>(below(4));
        for (int r = 0; r < rounds; ++r) {
            switch (below(10)) {
                case 0:  // random byte
                    if (!s.empty()) s[below(s.size())] = static_cast<char>(below(256));
                    break;
                case 1: {  // token from a dictionary of troublemakers
                    static const char* tokens[] = {"nan", "-1", "1e999", "4294967295", "1000000000000", "#", "\n",
                                                   "/", "//", "f ", "v ", "OFF", "0", "-0", "+", "3", " ", "\t",
                                                   "\r\n", "\"", "[", "]", "{", "}", ",", ":", "1e-400", "0x1",
                                                   "99999999999999999999999", "\xff"};
                    const std::string t = below(40) == 0 ? std::string(1, '\0') : tokens[below(std::size(tokens))];
                    s.insert(below(s.size() + 1), t);
                    break;
                }
                case 2:  // delete a range
                    if (!s.empty()) {
                        const std::size_t at = below(s.size());
                        s.erase(at, 1 + below(std::min<std::size_t>(16, s.size() - at)));
                    }
                    break;
                case 3:  // duplicate a range
                    if (!s.empty()) {
                        const std::size_t at = below(s.size());
                        const std::size_t len = 1 + below(std::min<std::size_t>(64, s.size() - at));
                        s.insert(below(s.size() + 1), s.substr(at, len));
                    }
                    break;
                case 4:  // truncate
                    s.resize(below(s.size() + 1));
                    break;
                case 5:  // change a digit
                case 6: {
                    for (int tries = 0; tries < 8 && !s.empty(); ++tries) {
                        const std::size_t at = below(s.size());
                        if (s[at] >= '0' && s[at] <= '9') {
                            s[at] = static_cast<char>('0' + below(10));
                            break;
                        }
                    }
                    break;
                }
                case 7: {  // swap two lines
                    std::vector<std::string> lines;
                    std::istringstream in(s);
                    for (std::string l; std::getline(in, l);) lines.push_back(l);
                    if (lines.size() >= 2) std::swap(lines[below(lines.size())], lines[below(lines.size())]);
                    s.clear();
                    for (const auto& l : lines) s += l + "\n";
                    break;
                }
                case 8:  // flip a bit
                    if (!s.empty()) s[below(s.size())] ^= static_cast<char>(1 << below(8));
                    break;
                default:  // random bytes
                    for (std::size_t k = 0, n = 1 + below(8); k < n; ++k) {
                        s.insert(below(s.size() + 1), 1, static_cast<char>(below(256)));
                    }
                    break;
            }
        }
        return s;
    }

private:
    std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(m_gen() % n); }
    std::mt19937_64 m_gen;
};

std::size_t lineCount(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')) + 1; }

void checkValid(const TriangleMesh& m) {
    for (const Vec3& p : m.vertices) ASSERT_TRUE(p.allFinite());
    for (const auto& t : m.triangles) {
        for (const auto i : t) ASSERT_LT(i, m.vertices.size());
    }
}

TEST(Fuzz, MutatedMeshFilesOnlyThrowParseError) {
    const std::string objBase =
        "# fuzz seed\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
        "f 1 2 3\nf 1/1 2/1 3/1 4/1\nf -1//1 -2//1 -3//1\nf 2/1/1 3/1/1 5/1/1\ng g\nusemtl m\n";
    const std::string offBase = kCubeOff + "# trailing comment\n";
    Mutator mutator(0xC0FFEE);
    const auto start = std::chrono::steady_clock::now();
    std::size_t parsed = 0, rejected = 0;
    for (int i = 0; i < 20000; ++i) {
        const bool isOff = (i % 2) == 0;
        const std::string input = mutator.mutate(isOff ? offBase : objBase);
        const std::string name = isOff ? "fuzz.off" : "fuzz.obj";
        try {
            std::istringstream in(input);
            const TriangleMesh m = isOff ? readOff(in, name) : readObj(in, name);
            checkValid(m);
            ++parsed;
        } catch (const ParseError& e) {
            ASSERT_EQ(e.file(), name);
            ASSERT_GE(e.line(), 1u) << e.what();
            ASSERT_LE(e.line(), lineCount(input) + 1) << e.what();
            ++rejected;
        } catch (const std::exception& e) {
            FAIL() << "input " << i << " threw a non-ParseError: " << e.what();
        }
        if (HasFatalFailure()) FAIL() << "input " << i;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    RecordProperty("fuzz_seconds", std::to_string(seconds));
    // Both outcomes must occur, else the mutator tests nothing.
    EXPECT_GT(parsed, 500u);
    EXPECT_GT(rejected, 5000u);
}

TEST(Fuzz, MutatedSceneFilesOnlyThrowParseError) {
    TempDir dir;
    dir.write("a.off", kCubeOff);
    dir.write("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string base = R"({
  "objects": [
    {"mesh": "a.off", "transform": [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]},
    {"mesh": "b.obj"},
    {"mesh": "a.off", "transform": [0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 2, 0, 0, 0, 1]}
  ]
}
)";
    Mutator mutator(0xBADC0DE);
    std::size_t parsed = 0, rejected = 0;
    for (int i = 0; i < 1000; ++i) {
        const std::string input = mutator.mutate(base);
        const std::string path = dir.write("scene.json", input);
        try {
            const auto scene = readSceneFile(path);
            for (const auto& o : scene) checkValid(*o.mesh);
            ++parsed;
        } catch (const ParseError& e) {
            ASSERT_EQ(e.file(), path) << e.what();
            ASSERT_GE(e.line(), 1u) << e.what();
            ASSERT_LE(e.line(), lineCount(input) + 1) << e.what();
            ++rejected;
        } catch (const std::exception& e) {
            FAIL() << "input " << i << " threw a non-ParseError: " << e.what();
        }
        if (HasFatalFailure()) FAIL() << "input " << i;
    }
    EXPECT_GT(parsed, 25u);
    EXPECT_GT(rejected, 250u);
}

}  // namespace
}  // namespace cullide::io
