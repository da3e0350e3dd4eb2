// Hostile input (issue 14): bounded time, memory and messages; messages that say what is wrong.
#include "ReaderSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <sstream>
#include <streambuf>
#include <string>

namespace cullide::io {
namespace {

using namespace cullide::test;

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
/// The most negative ones too: tokens - n overflowed for n = -2^63 + 1 (found by the fuzzer again).
TEST(HostileInput, AVertexOfHugeIntegersIsAVertex) {
    for (const char* first : {"9223372036854775807", "-9223372036854775807"}) {
        const TriangleMesh m = off(std::string("OFF\n3 1 0\n") + first + " 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        ASSERT_EQ(m.vertices.size(), 3u) << first;
        EXPECT_EQ(m.vertices[0][0], std::stod(first)) << first;
        EXPECT_EQ(m.triangles.size(), 1u) << first;
    }
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

}  // namespace
}  // namespace cullide::io
