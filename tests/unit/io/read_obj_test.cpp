// The OBJ reader (readObj): every face variant, other records ignored, negative and forward indices, malformed
// records rejected with a ParseError at the right line.
#include "ReaderSupport.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide::io {
namespace {

using namespace cullide::test;

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

}  // namespace
}  // namespace cullide::io
