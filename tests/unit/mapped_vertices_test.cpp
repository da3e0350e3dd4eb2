// The slots of the transformed meshes' own vertices (MappedVertices.h): one per mesh, shared by the objects that use
// it, kept across uploads, written again from the first value that changed; dropped when unused for 64 frames, and
// the store starts over when the dropped slots outweigh the live ones.
#include "MappedVertices.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide::test {
namespace {

TEST(MappedVertices, OneSlotPerMeshKeptAcrossUploads) {
    const TriangleMesh a = scenes::makeBox(Vec3(1, 2, 3));
    TriangleMesh b = scenes::makeBox(Vec3(0.5, 0.5, 0.5));
    MappedVertices slots;
    std::vector<double> values;
    EXPECT_FALSE(slots.beginUpload(values));
    const MappedVertices::Slot first = slots.place(a, values);
    const MappedVertices::Slot again = slots.place(a, values);  // a second object with the same mesh
    const MappedVertices::Slot other = slots.place(b, values);
    EXPECT_FALSE(first.placedBefore);
    EXPECT_TRUE(again.placedBefore);
    EXPECT_EQ(again.base, first.base);
    EXPECT_EQ(other.base, a.vertices.size());
    ASSERT_EQ(values.size(), 3 * (a.vertices.size() + b.vertices.size()));
    EXPECT_EQ(MappedVertices::write(a, first.base, values), 0u) << "a new slot is written from its start";
    EXPECT_EQ(MappedVertices::write(b, other.base, values), 3 * a.vertices.size());
    EXPECT_EQ(values[3 * other.base + 2], b.vertices[0].z());

    // The next upload: the same slots; only what changed is reported.
    EXPECT_FALSE(slots.beginUpload(values));
    const MappedVertices::Slot kept = slots.place(b, values);
    EXPECT_EQ(kept.base, other.base);
    EXPECT_FALSE(kept.placedBefore) << "first use in this upload";
    EXPECT_EQ(MappedVertices::write(b, kept.base, values), values.size()) << "nothing changed";
    b.vertices[3].y() += 0.25;  // vertex 3 moves along y
    EXPECT_EQ(MappedVertices::write(b, kept.base, values), 3 * (std::size_t{kept.base} + 3) + 1);

    // The mesh grew (same address, more vertices): a new slot after the others.
    b.vertices.push_back(Vec3(9, 9, 9));
    const MappedVertices::Slot grown = slots.place(b, values);
    EXPECT_EQ(grown.base, a.vertices.size() + b.vertices.size() - 1);
}

TEST(MappedVertices, UnusedSlotsAreDroppedAndTheStoreStartsOver) {
    std::vector<TriangleMesh> meshes(8, scenes::makeBox(Vec3(1, 1, 1)));
    for (TriangleMesh& m : meshes)  // enough vertices that the dropped slots outweigh the slack
        for (int k = 0; k < 200; ++k) m.vertices.push_back(Vec3(k, 0, 0));
    MappedVertices slots;
    std::vector<double> values;
    slots.beginUpload(values);
    for (const TriangleMesh& m : meshes) slots.place(m, values);
    const std::size_t all = values.size();
    bool startedOver = false;
    int uploads = 0;
    for (; uploads < 200 && !startedOver; ++uploads) {  // only the first mesh stays in use
        slots.beginFrame();
        for (int cluster = 0; cluster < 3 && !startedOver; ++cluster)  // uploads within a frame do not age slots
            startedOver = slots.beginUpload(values);
        if (!startedOver) {
            EXPECT_EQ(values.size(), all);
        }
        const MappedVertices::Slot s = slots.place(meshes[0], values);
        if (startedOver) {
            EXPECT_EQ(s.base, 0u);
            EXPECT_EQ(values.size(), 3 * meshes[0].vertices.size());
        }
    }
    EXPECT_TRUE(startedOver);
    EXPECT_GT(uploads, 60) << "slots are kept for 64 frames (kKeepFrames)";
}

}  // namespace
}  // namespace cullide::test
