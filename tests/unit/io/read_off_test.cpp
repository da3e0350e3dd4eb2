// The OFF reader (readOff): good files read exactly (polygons fanned, comments, header variants, colours), and every
// kind of malformed input rejected with a ParseError at the right line, without huge allocations.
#include "ReaderSupport.h"

#include <gtest/gtest.h>

#include <random>
#include <sstream>
#include <streambuf>
#include <string>
#include <utility>
#include <vector>

namespace cullide::io {
namespace {

using namespace cullide::test;

/// A stream that cannot seek (like a pipe): the reader cannot learn its size in advance.
class NonSeekableBuf : public std::streambuf {
public:
    explicit NonSeekableBuf(std::string s) : m_s(std::move(s)) { setg(m_s.data(), m_s.data(), m_s.data() + m_s.size()); }

private:
    std::string m_s;
};

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

}  // namespace
}  // namespace cullide::io
