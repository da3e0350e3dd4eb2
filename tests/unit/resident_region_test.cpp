// The device's resident region of static meshes (MeshCache.h), without GL: its origin kept while the cluster stays
// near and alike, started over when most of it is stale.
#include "MeshCache.h"

#include <gtest/gtest.h>

#include <vector>

namespace cullide::test {
namespace {

TEST(ResidentRegion, KeepsItsOriginWhileTheClusterStaysNearAndAlike) {
    ResidentRegion region;
    const Vec3 origin = region.fit(Vec3(10, 0, 0), 4.0, 1000);
    EXPECT_EQ(origin, Vec3(10, 0, 0));
    StaticEntry e;
    const ResidentRegion::Place first = region.place(e, 8, 12);
    EXPECT_TRUE(first.appended);
    EXPECT_EQ(first.baseTriangle, 0u);
    EXPECT_EQ(region.triangles(), 12u);
    // Moved by less than half the extent, same size: the region and the mesh in it stay.
    EXPECT_EQ(region.fit(Vec3(11.9, 0, 0), 4.0, 1000), origin);
    const ResidentRegion::Place again = region.place(e, 8, 12);
    EXPECT_FALSE(again.appended);
    EXPECT_EQ(again.baseTriangle, 0u);
    EXPECT_EQ(region.triangles(), 12u);
    // Each of these starts over: moved beyond half the extent, grown beyond 2x, shrunk below a quarter.
    for (const auto& [centre, extent] : std::vector<std::pair<Vec3, double>>{
             {Vec3(12.1, 0, 0), 4.0}, {Vec3(10, 0, 0), 8.1}, {Vec3(10, 0, 0), 0.9}}) {
        ResidentRegion r;
        r.fit(Vec3(10, 0, 0), 4.0, 1000);
        StaticEntry s;
        r.place(s, 8, 12);
        EXPECT_EQ(r.fit(centre, extent, 1000), centre) << centre.transpose() << " " << extent;
        EXPECT_EQ(r.triangles(), 0u);
        EXPECT_TRUE(r.place(s, 8, 12).appended);
    }
}

TEST(ResidentRegion, StartsOverWhenMostOfItIsStale) {
    ResidentRegion region;
    region.fit(Vec3::Zero(), 1.0, 0);
    std::vector<StaticEntry> entries(10);
    for (StaticEntry& e : entries) region.place(e, 10000, 20000);
    EXPECT_EQ(region.triangles(), 200000u);
    // 200,000 resident triangles, 70,000 of them still used: 200,000 <= 2 * 70,000 + 65,536 holds.
    region.fit(Vec3::Zero(), 1.0, 70000);
    EXPECT_EQ(region.triangles(), 200000u);
    // 60,000 used: 200,000 > 2 * 60,000 + 65,536, so the region is rebuilt and every mesh is written again.
    region.fit(Vec3::Zero(), 1.0, 60000);
    EXPECT_EQ(region.triangles(), 0u);
    EXPECT_TRUE(region.place(entries[3], 10000, 20000).appended);
}

}  // namespace
}  // namespace cullide::test
