// clustersOf: the groups of objects that the visibility levels run on, each with its own views (issue #13, item 3).
// Objects that can meet share a cluster; a far outlier never stretches another cluster's view.
#include "FrameObjects.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace cullide {
namespace {

ValidatedObject at(double x, double size = 1.0) {
    ValidatedObject o;
    o.valid = true;
    o.isMesh = true;
    o.box.grow(Vec3(x, 0, 0));
    o.box.grow(Vec3(x + size, size, size));
    return o;
}

using Pairs = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
using Clusters = std::vector<std::vector<std::uint32_t>>;

TEST(Clusters, ComponentsOfTheOverlapGraphStayTogether) {
    // A chain 0-1-2 (each overlapping the next) and a pair 3-4 nearby: one compact cluster.
    const std::vector<ValidatedObject> objects = {at(0), at(0.9), at(1.8), at(3.5), at(4.2)};
    const std::vector<std::uint8_t> all(objects.size(), 1);
    const Clusters c = clustersOf(all, Pairs{{0, 1}, {1, 2}, {3, 4}}, objects);
    EXPECT_EQ(c, (Clusters{{0, 1, 2, 3, 4}}));
}

TEST(Clusters, FarGroupsGetTheirOwnCluster) {
    for (double s : {1e3, 1e8, 1e14, 1e30, 1e300}) {
        const std::vector<ValidatedObject> objects = {at(0), at(0.5), at(s), at(s + 0.5), at(-s)};
        const std::vector<std::uint8_t> all(objects.size(), 1);
        const Clusters c = clustersOf(all, Pairs{{0, 1}, {2, 3}}, objects);
        // The lone object 4 has no partner but is a member: its own cluster (the caller decides membership).
        EXPECT_EQ(c, (Clusters{{0, 1}, {2, 3}, {4}})) << "s = " << s;
    }
}

TEST(Clusters, MergesOnlyWithinTheSpread) {
    // Two unit pairs whose union box is up to kClusterSpread times a part's extent share a cluster; farther, not.
    const double near = kClusterSpread * 1.5 - 1.5;  // union extent = exactly the spread times 1.5
    const std::vector<ValidatedObject> objects = {at(0), at(0.5), at(near), at(near + 0.5)};
    const std::vector<std::uint8_t> all(objects.size(), 1);
    EXPECT_EQ(clustersOf(all, Pairs{{0, 1}, {2, 3}}, objects), (Clusters{{0, 1, 2, 3}}));
    const std::vector<ValidatedObject> apart = {at(0), at(0.5), at(near + 0.01), at(near + 0.51)};
    EXPECT_EQ(clustersOf(all, Pairs{{0, 1}, {2, 3}}, apart), (Clusters{{0, 1}, {2, 3}}));
}

TEST(Clusters, NonMembersAndTheirPairsAreIgnored) {
    const std::vector<ValidatedObject> objects = {at(0), at(0.5), at(1.0), at(50)};
    const std::vector<std::uint8_t> member = {1, 0, 1, 1};
    // 0 and 2 meet only through 1, which is not a member: separate components, merged as compact neighbours.
    const Clusters c = clustersOf(member, Pairs{{0, 1}, {1, 2}}, objects);
    EXPECT_EQ(c, (Clusters{{0, 2}, {3}}));
    EXPECT_TRUE(clustersOf(std::vector<std::uint8_t>(4, 0), Pairs{{0, 1}}, objects).empty());
}

}  // namespace
}  // namespace cullide
