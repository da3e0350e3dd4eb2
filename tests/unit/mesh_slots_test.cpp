// The places of the meshes that are not static (MeshSlots.h): one per object's mesh after the resident region, kept
// across uploads and frames while the mesh comes and goes, the mapped meshes' vertices after every other's; places
// free up after 64 frames unused, and all start over when the region reaches into them or freed places outweigh the
// used.
#include "MeshSlots.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

namespace cullide::test {
namespace {

TEST(MeshSlots, AMeshKeepsItsPlaceWhileOthersComeAndGo) {
    const TriangleMesh a = scenes::makeBox(Vec3(1, 2, 3));
    const TriangleMesh b = scenes::makeSphere(1.0, 8, 4);
    const TriangleMesh c = scenes::makeTorus(1.0, 0.2, 8, 6);
    MeshSlots slots;
    slots.beginFrame();
    EXPECT_TRUE(slots.beginUpload(100, 50)) << "the first upload places everything";
    const MeshSlots::Slot pa = slots.place(0, a, false), pb = slots.place(1, b, false), pc = slots.place(2, c, false);
    EXPECT_EQ(pa.baseVertex, 100u) << "after the region";
    EXPECT_EQ(pa.baseTriangle, 50u);
    EXPECT_EQ(pb.baseVertex, 100u + a.vertices.size());
    EXPECT_EQ(pc.baseTriangle, 50u + a.triangles.size() + b.triangles.size());
    for (int frame = 0; frame < 3; ++frame) {  // b leaves for a while, and comes back
        slots.beginFrame();
        EXPECT_FALSE(slots.beginUpload(100, 50));
        EXPECT_EQ(slots.place(2, c, false).baseVertex, pc.baseVertex);
        EXPECT_EQ(slots.place(0, a, false).baseTriangle, pa.baseTriangle);
        if (frame == 2) {
            EXPECT_EQ(slots.place(1, b, false).baseVertex, pb.baseVertex);
        }
    }
    EXPECT_EQ(slots.plainVertexEnd(), 100u + a.vertices.size() + b.vertices.size() + c.vertices.size());
    // Another mesh for object 1 gets a place of its own.
    EXPECT_GE(slots.place(1, c, false).baseVertex, pc.baseVertex + c.vertices.size());
    // So does a mesh whose triangles grow or shrink with its vertices as they were (a piece breaking off).
    TriangleMesh d = scenes::makeBox(Vec3(1, 1, 1));
    const MeshSlots::Slot pd = slots.place(3, d, false);
    d.triangles.push_back(d.triangles.front());
    const MeshSlots::Slot grown = slots.place(3, d, false);
    EXPECT_NE(grown.baseTriangle, pd.baseTriangle) << "its triangles would run into the next place's";
    // The region reaching into the places: every mesh is placed anew after it.
    slots.beginFrame();
    EXPECT_TRUE(slots.beginUpload(101, 50));
    EXPECT_EQ(slots.place(2, c, false).baseVertex, 101u);
}

TEST(MeshSlots, TheMappedMeshesLieAfterTheOthersAndMoveOnlyWhenTheOthersOutgrowTheirRoom) {
    const TriangleMesh small = scenes::makeBox(Vec3(1, 1, 1));
    const TriangleMesh big = scenes::makeSphere(1.0, 64, 32);
    MeshSlots slots;
    slots.beginFrame();
    slots.beginUpload(0, 0);
    const MeshSlots::Slot plain = slots.place(0, small, false);
    const MeshSlots::Slot mapped = slots.place(1, small, true);
    EXPECT_EQ(plain.baseVertex, 0u);
    EXPECT_GE(mapped.baseVertex, plain.baseVertex + small.vertices.size()) << "after the plain meshes' room";
    EXPECT_EQ(slots.place(0, small, true).baseVertex, mapped.baseVertex + small.vertices.size())
        << "the same mesh mapped is another place";
    slots.beginFrame();
    slots.beginUpload(0, 0);
    EXPECT_EQ(slots.place(0, small, false).baseVertex, plain.baseVertex);
    const MeshSlots::Slot bigPlace = slots.place(2, big, false);  // over the room: the mapped ones move after it
    const MeshSlots::Slot moved = slots.place(1, small, true);
    EXPECT_GE(moved.baseVertex, bigPlace.baseVertex + big.vertices.size());
    EXPECT_NE(moved.baseVertex, mapped.baseVertex);
    EXPECT_EQ(slots.place(1, small, true).baseVertex, moved.baseVertex) << "kept after that";
}

TEST(MeshSlots, PlacesUnusedFor64FramesAreFreedAndTheRestPlacedAnewWhenFreedOutweighUsed) {
    const TriangleMesh big = scenes::makeSphere(1.0, 256, 128);  // 65,536 triangles: worth starting over for
    const TriangleMesh small = scenes::makeBox(Vec3(1, 1, 1));
    MeshSlots slots;
    slots.beginFrame();
    slots.beginUpload(0, 0);
    slots.place(0, big, false);
    const MeshSlots::Slot kept = slots.place(1, small, false);
    bool startedOver = false;
    for (int frame = 0; frame < 70 && !startedOver; ++frame) {  // only the small mesh goes on
        slots.beginFrame();
        startedOver = slots.beginUpload(0, 0);
        const MeshSlots::Slot now = slots.place(1, small, false);
        EXPECT_EQ(now.baseVertex, startedOver ? 0u : kept.baseVertex) << frame << ": placed anew at the front";
    }
    EXPECT_TRUE(startedOver) << "the big mesh's place was never freed";
}

}  // namespace
}  // namespace cullide::test
