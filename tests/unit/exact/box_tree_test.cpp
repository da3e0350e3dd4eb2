// The exact stage's box tree against brute force: every overlapping (closed-interval) box pair exactly once,
// whatever the split of the descent, for soups, duplicates, degenerate and huge boxes.
#include "FrameObjects.h"
#include "TriangleOrders.h"
#include "exact/BoxTree.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

namespace cullide {
namespace {

std::vector<TrianglePair> bruteForce(const std::vector<Aabb>& a, const std::vector<std::uint32_t>& listA,
                                     const std::vector<Aabb>& b, const std::vector<std::uint32_t>& listB) {
    std::vector<TrianglePair> out;
    for (std::uint32_t i : listA)
        for (std::uint32_t j : listB)
            if (a[i].overlaps(b[j])) out.push_back({i, j});
    std::sort(out.begin(), out.end());
    return out;
}

std::vector<TrianglePair> viaTree(const std::vector<Aabb>& a, const std::vector<std::uint32_t>& listA,
                                  const std::vector<Aabb>& b, const std::vector<std::uint32_t>& listB,
                                  std::size_t target) {
    BoxTree ta;
    BoxTree tb;
    ta.build(a, listA);
    tb.build(b, listB);
    std::vector<BoxTree::NodePair> frontier;
    std::vector<BoxTree::NodePair> stack;
    BoxTree::split(ta, tb, target, frontier);
    std::vector<TrianglePair> out;
    for (const BoxTree::NodePair& p : frontier) BoxTree::leafPairs(ta, tb, p, stack, out);
    std::sort(out.begin(), out.end());
    return out;
}

/// Every box of `a` and `b` takes part: the tree's pairs must equal brute force's for each split target, and there
/// must be some, or the comparison means little.
void expectMatchesBruteForce(const std::vector<Aabb>& a, const std::vector<Aabb>& b,
                             std::initializer_list<std::size_t> targets, double what = 0.0) {
    std::vector<std::uint32_t> listA(a.size()), listB(b.size());
    std::iota(listA.begin(), listA.end(), 0u);
    std::iota(listB.begin(), listB.end(), 0u);
    const auto expected = bruteForce(a, listA, b, listB);
    ASSERT_FALSE(expected.empty()) << what;
    for (const std::size_t target : targets)
        EXPECT_EQ(viaTree(a, listA, b, listB, target), expected) << what << ", target " << target;
}

std::vector<Aabb> randomBoxes(std::mt19937& rng, std::size_t n, double spread, double size, double offset) {
    std::uniform_real_distribution<double> pos(-spread, spread);
    std::uniform_real_distribution<double> ext(0.0, size);
    std::vector<Aabb> boxes(n);
    for (Aabb& box : boxes) {
        for (int k = 0; k < 3; ++k) {
            box.min[k] = offset + pos(rng);
            box.max[k] = box.min[k] + ext(rng);
        }
    }
    return boxes;
}

std::vector<std::uint32_t> everyOther(std::size_t n, std::uint32_t step) {
    std::vector<std::uint32_t> list;
    for (std::uint32_t i = 0; i < n; i += step) list.push_back(i);
    return list;
}

TEST(BoxTree, EveryOverlappingPairExactlyOnceForAnySplit) {
    std::mt19937 rng(7);
    for (const std::size_t n : {1u, 2u, 7u, 8u, 9u, 63u, 64u, 65u, 700u, 3000u}) {
        const auto a = randomBoxes(rng, n, 10.0, 1.5, 0.0);
        const auto b = randomBoxes(rng, n / 2 + 1, 10.0, 2.5, 0.5);
        const auto listA = everyOther(a.size(), 1);
        const auto listB = everyOther(b.size(), n > 8 ? 2 : 1);  // a subset: only listed boxes take part
        const auto expected = bruteForce(a, listA, b, listB);
        for (const std::size_t target : {1u, 2u, 16u, 1000u, 100000u}) {
            const auto got = viaTree(a, listA, b, listB, target);
            ASSERT_EQ(got, expected) << "n " << n << " target " << target;  // sorted: a duplicate would show
        }
    }
}

TEST(BoxTree, TouchingDegenerateAndDuplicateBoxes) {
    // Boxes that only touch (closed intervals), points, flat boxes and exact duplicates: the float pruning must
    // not lose a pair that the double test accepts.
    std::vector<Aabb> a;
    std::vector<Aabb> b;
    for (int i = 0; i < 50; ++i) {
        const double x = 0.1 * i;
        a.push_back({Vec3(x, 0, 0), Vec3(x + 0.1, 1, 1)});
        a.push_back({Vec3(x, 0.3, 0.3), Vec3(x, 0.3, 0.3)});  // a point
        b.push_back({Vec3(x + 0.1, 1, 1), Vec3(x + 0.2, 2, 2)});  // touches a's corner
        b.push_back({Vec3(x, 0.3, 0.3), Vec3(x, 0.3, 0.3)});      // the same point
        b.push_back({Vec3(x, 0, 0), Vec3(x + 0.1, 1, 0)});         // flat, on a's face
    }
    expectMatchesBruteForce(a, b, {1, 64, 100000});
}

TEST(BoxTree, CoordinatesFarFromTheOriginAndBeyondFloatRange) {
    // Tiny boxes far out (float spacing there is larger than the boxes) and boxes beyond the float range: the
    // float boxes are coarse or unbounded there, the double decision still exact.
    std::mt19937 rng(11);
    for (const double offset : {1e7, 1e15, 1e38, 1e300, 1.7e308}) {
        const auto a = randomBoxes(rng, 400, offset * 1e-9, offset * 1e-10, offset);
        const auto b = randomBoxes(rng, 300, offset * 1e-9, offset * 2e-10, offset);
        expectMatchesBruteForce(a, b, {8}, offset);
    }
}

TEST(BoxTree, BoxesSpanningTheWholeDoubleRange) {
    // Centres and extents overflow to infinity here (the Morton scale becomes 0, inf * 0 is NaN): the order
    // degrades, the answer must not.
    std::vector<Aabb> a, b;
    const double big = 1.7e308;
    for (int i = 0; i < 40; ++i) {
        const double s = (i % 2 ? 1.0 : -1.0) * big * (0.5 + 0.01 * i);
        a.push_back({Vec3(s, -big, 0.0), Vec3(std::max(s, 0.0), big, 1.0)});
        b.push_back({Vec3(-big, s, 0.5), Vec3(big, std::max(s, 0.0), 0.5 + 1e-3 * i)});
    }
    a.push_back({Vec3(-big, -big, -big), Vec3(big, big, big)});
    expectMatchesBruteForce(a, b, {1, 8, 100000});
}

TEST(BoxTree, EmptyListsAndDisjointTrees) {
    std::mt19937 rng(3);
    const auto a = randomBoxes(rng, 100, 1.0, 0.1, 0.0);
    const auto b = randomBoxes(rng, 100, 1.0, 0.1, 100.0);
    EXPECT_TRUE(viaTree(a, {}, b, everyOther(b.size(), 1), 8).empty());
    EXPECT_TRUE(viaTree(a, everyOther(a.size(), 1), b, {}, 8).empty());
    EXPECT_TRUE(viaTree(a, everyOther(a.size(), 1), b, everyOther(b.size(), 1), 8).empty());
}

TEST(BoxTree, RebuildReusesMemoryWithoutStaleNodes) {
    // A tree rebuilt smaller must not keep levels or leaves of its larger past.
    std::mt19937 rng(5);
    BoxTree ta;
    BoxTree tb;
    const auto big = randomBoxes(rng, 5000, 10.0, 1.0, 0.0);
    ta.build(big, everyOther(big.size(), 1));
    const auto a = randomBoxes(rng, 20, 10.0, 1.0, 0.0);
    const auto b = randomBoxes(rng, 5000, 10.0, 1.0, 0.0);
    const auto listA = everyOther(a.size(), 1);
    const auto listB = everyOther(b.size(), 1);
    ta.build(a, listA);
    tb.build(b, listB);
    std::vector<BoxTree::NodePair> frontier;
    std::vector<BoxTree::NodePair> stack;
    BoxTree::split(ta, tb, 4, frontier);
    std::vector<TrianglePair> got;
    for (const BoxTree::NodePair& p : frontier) BoxTree::leafPairs(ta, tb, p, stack, got);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, bruteForce(a, listA, b, listB));
}

TEST(BoxTree, BuiltOnWorkersTheSameTreeAsOnOneThread) {
    // The build's steps run in chunks of the list, smaller on larger pools: any number of workers must give the same
    // leaves in the same order, and the pairs of brute force, across chunk boundaries and for lists that skip boxes.
    std::mt19937 rng(13);
    TaskPool two(2), five(5);
    for (const std::size_t n : {1u, 4095u, 4096u, 4097u, 12289u, 40000u}) {
        const auto a = randomBoxes(rng, n, 10.0, 0.2, 0.0);
        const auto listA = everyOther(a.size(), n > 5000 ? 3 : 1);
        BoxTree serial, onTwo, onFive;
        serial.build(a, listA);
        onTwo.build(a, listA, &two);
        onFive.build(a, listA, &five);
        ASSERT_EQ(onTwo.leafTriangles(), serial.leafTriangles()) << n;
        ASSERT_EQ(onFive.leafTriangles(), serial.leafTriangles()) << n;
        const auto b = randomBoxes(rng, 200, 10.0, 1.0, 0.0);
        const auto listB = everyOther(b.size(), 1);
        BoxTree tb;
        tb.build(b, listB, &two);
        std::vector<BoxTree::NodePair> frontier, stack;
        BoxTree::split(onFive, tb, 64, frontier);
        std::vector<TrianglePair> got;
        for (const BoxTree::NodePair& p : frontier) BoxTree::leafPairs(onFive, tb, p, stack, got);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, bruteForce(a, listA, b, listB)) << n;
    }
}

TEST(BoxTree, SplitManyIsSplitForEachJobOnAnyPool) {
    // Several tree pairs split together, their rounds on a pool's workers: each job's node pairs must be split()'s,
    // in its order, whatever the other jobs (a large one whose rounds are cut into chunks, small ones that stop
    // early or only have leaf pairs, an empty tree, roots apart) and the number of workers.
    std::mt19937 rng(29);
    std::vector<BoxTree> trees(7);
    const auto build = [&](BoxTree& tree, std::size_t n, double offset) {
        auto boxes = randomBoxes(rng, n, 10.0, 0.5, 0.0);
        for (Aabb& b : boxes) b = Aabb{b.min + Vec3::Constant(offset), b.max + Vec3::Constant(offset)};
        tree.build(boxes, everyOther(n, 1));
    };
    build(trees[0], 20000, 0.0);
    build(trees[1], 8000, 0.0);
    build(trees[2], 3, 0.0);
    build(trees[3], 60, 0.0);
    build(trees[5], 50, 100.0);  // trees[4] stays empty
    build(trees[6], 500, 0.0);
    const std::vector<BoxTree::SplitJob> jobs{{&trees[0], &trees[1], 4096}, {&trees[2], &trees[3], 1000},
                                              {&trees[3], &trees[1], 8},     {&trees[4], &trees[1], 64},
                                              {&trees[5], &trees[0], 64},    {&trees[6], &trees[0], 1},
                                              {&trees[1], &trees[6], 300}};
    TaskPool one(1), three(3);
    for (TaskPool* pool : {static_cast<TaskPool*>(nullptr), &one, &three}) {
        std::vector<std::vector<BoxTree::NodePair>> got(2, std::vector<BoxTree::NodePair>(5));  // stale: replaced
        BoxTree::splitMany(jobs, pool, got);
        ASSERT_GE(got.size(), jobs.size());
        std::size_t pairs = 0;
        for (std::size_t j = 0; j < jobs.size(); ++j) {
            std::vector<BoxTree::NodePair> want;
            BoxTree::split(*jobs[j].a, *jobs[j].b, jobs[j].target, want);
            ASSERT_EQ(got[j].size(), want.size()) << "job " << j;
            for (std::size_t i = 0; i < want.size(); ++i) {
                const auto& g = got[j][i];
                const auto& w = want[i];
                ASSERT_TRUE(g.levelA == w.levelA && g.nodeA == w.nodeA && g.levelB == w.levelB && g.nodeB == w.nodeB)
                    << "job " << j << ", pair " << i;
            }
            pairs += want.size();
        }
        EXPECT_GE(got[0].size(), 4096u) << "the large job must reach its target";
        EXPECT_TRUE(got[3].empty() && got[4].empty());
        EXPECT_GT(pairs, 4096u + 100u);
    }
}

TEST(BoxTree, LeavesInMortonOrderTiesInListOrder) {
    // Boxes along the x axis: their Morton order is their order along x. Each position holds three copies (equal
    // codes), listed in different chunks: they must stay in list order, whatever the number of workers.
    constexpr std::uint32_t kPositions = 3000;
    std::vector<Aabb> boxes(3 * kPositions);
    std::vector<std::uint32_t> list;
    std::vector<std::uint32_t> position(boxes.size());
    for (std::uint32_t copy = 0; copy < 3; ++copy) {
        for (std::uint32_t i = 0; i < kPositions; ++i) {
            const std::uint32_t at = kPositions - 1 - i;  // listed from +x to -x: the sort must reverse them
            const std::uint32_t t = copy * kPositions + at;
            boxes[t] = {Vec3(at, 0, 0), Vec3(at + 0.5, 1, 1)};
            position[t] = at;
            list.push_back(t);
        }
    }
    TaskPool three(3);
    for (TaskPool* pool : {static_cast<TaskPool*>(nullptr), &three}) {
        BoxTree tree;
        tree.build(boxes, list, pool);
        const std::vector<std::uint32_t>& leaves = tree.leafTriangles();
        ASSERT_EQ(leaves.size(), list.size());
        // 1023 Morton cells over 3000 positions: positions share cells, so order by cell, then by list order. The
        // centre is at + 0.25 and the bounds [0, kPositions - 0.5] along x.
        auto cell = [&](std::uint32_t t) {
            return static_cast<int>((position[t] + 0.25) * (1023.0 / (kPositions - 0.5)));
        };
        auto rank = [&](std::uint32_t t) { return (t / kPositions) * kPositions + (kPositions - 1 - position[t]); };
        for (std::size_t i = 1; i < leaves.size(); ++i) {
            const int before = cell(leaves[i - 1]);
            const int after = cell(leaves[i]);
            ASSERT_LE(before, after) << "leaf " << i;
            if (before == after) {  // the same cell: list order (copy, then from +x to -x)
                ASSERT_LT(rank(leaves[i - 1]), rank(leaves[i])) << "leaf " << i;
            }
        }
    }
}

TEST(BoxTree, RebuildsIntoTheMemoryOfEarlierFrames) {
    // Rebuilt every frame: after a small frame (a GPU frame's few survivors, a contact that shrank) a slightly larger
    // one than ever before must not get a fresh exact-fit buffer (a page fault per 4 KiB of it, every time).
    std::mt19937 rng(5);
    const std::vector<Aabb> boxes = randomBoxes(rng, 70000, 1.0, 0.01, 0.0);
    auto firstN = [](std::size_t n) {
        std::vector<std::uint32_t> list(n);
        std::iota(list.begin(), list.end(), 0u);
        return list;
    };
    BoxTree tree;
    tree.build(boxes, firstN(60000));
    const std::uint32_t* leaves = tree.leafTriangles().data();
    tree.build(boxes, firstN(3000));
    tree.build(boxes, firstN(62000));
    EXPECT_EQ(tree.leafTriangles().data(), leaves);
    EXPECT_EQ(tree.size(), 62000u);
    std::vector<std::uint32_t> sorted = tree.leafTriangles();
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(sorted, firstN(62000));
}

}  // namespace
}  // namespace cullide

namespace cullide {
namespace {

std::vector<TrianglePair> pairsOf(const BoxTree& ta, const BoxTree& tb) {
    std::vector<BoxTree::NodePair> frontier, stack;
    BoxTree::split(ta, tb, 64, frontier);
    std::vector<TrianglePair> out;
    for (const BoxTree::NodePair& p : frontier) BoxTree::leafPairs(ta, tb, p, stack, out);
    std::sort(out.begin(), out.end());
    return out;
}

TEST(BoxTree, FollowingAKeptOrderTakesTheListsTrianglesInThatOrder) {
    // A refit in a kept order (a shuffled permutation here: any order must do) instead of a sort: the leaves are
    // exactly the listed triangles, in the order's sequence, on any number of workers, with brute force's pairs.
    std::mt19937 rng(29);
    TaskPool three(3);
    for (const std::size_t n : {9u, 4096u, 4097u, 30000u}) {
        const auto a = randomBoxes(rng, n, 10.0, 0.3, 0.0);
        std::vector<std::uint32_t> order(n);
        std::iota(order.begin(), order.end(), 0u);
        std::shuffle(order.begin(), order.end(), rng);
        const auto b = randomBoxes(rng, 300, 10.0, 1.0, 0.0);
        const auto listB = everyOther(b.size(), 1);
        BoxTree tb;
        tb.build(b, listB);
        for (const std::uint32_t step : {1u, 3u, 8u}) {  // 1/8 of the mesh: still followed
            const auto listA = everyOther(a.size(), step);
            std::vector<std::uint32_t> expectedLeaves;
            for (const std::uint32_t t : order)
                if (t % step == 0) expectedLeaves.push_back(t);
            for (TaskPool* pool : {static_cast<TaskPool*>(nullptr), &three}) {
                BoxTree ta;
                ta.build(a, listA, pool, &order);
                ASSERT_TRUE(ta.followedOrder()) << n << " step " << step;
                ASSERT_EQ(ta.leafTriangles(), expectedLeaves) << n << " step " << step;
                EXPECT_EQ(pairsOf(ta, tb), bruteForce(a, listA, b, listB)) << n << " step " << step;
            }
        }
    }
}

TEST(BoxTree, AnOrderThatCannotBeFollowedIsIgnored) {
    // Sorted instead, with the same pairs: a list under 1/8 of the order (walking the order would cost more), a list
    // that is not strictly increasing (a triangle twice), a triangle beyond the order, an order shorter than the mesh
    // (it does not hold every listed triangle). (An order is a permutation of the mesh's triangles: build()'s
    // precondition, which TriangleOrders meets.)
    std::mt19937 rng(31);
    const auto a = randomBoxes(rng, 2000, 10.0, 0.5, 0.0);
    const auto b = randomBoxes(rng, 300, 10.0, 1.0, 0.0);
    const auto listB = everyOther(b.size(), 1);
    BoxTree tb;
    tb.build(b, listB);
    std::vector<std::uint32_t> order(a.size());
    std::iota(order.begin(), order.end(), 0u);
    std::vector<std::uint32_t> twice = everyOther(a.size(), 2);
    twice.insert(twice.begin() + 10, twice[10]);
    const std::vector<std::uint32_t> shortOrder(order.begin(), order.begin() + 1500);
    std::vector<std::uint32_t> missing(order.begin() + 1, order.end());  // a permutation without triangle 0
    struct Case {
        const char* what;
        std::vector<std::uint32_t> list;
        const std::vector<std::uint32_t>* order;
    };
    const Case cases[] = {{"a ninth", everyOther(a.size(), 9), &order},
                          {"a triangle twice", twice, &order},
                          {"beyond the order", everyOther(a.size(), 1), &shortOrder},
                          {"not in the order", everyOther(a.size(), 1), &missing}};
    TaskPool two(2);
    for (const Case& c : cases) {
        for (TaskPool* pool : {static_cast<TaskPool*>(nullptr), &two}) {
            BoxTree ta;
            ta.build(a, c.list, pool, c.order);
            EXPECT_FALSE(ta.followedOrder()) << c.what;
            BoxTree sorted;
            sorted.build(a, c.list, pool);
            EXPECT_EQ(ta.leafTriangles(), sorted.leafTriangles()) << c.what;
            EXPECT_EQ(pairsOf(ta, tb), bruteForce(a, c.list, b, listB)) << c.what;
        }
    }
}

TEST(BoxTree, AWholeMeshTreeIsTheTreeOfEveryTrianglesBoxInTheGivenOrder) {
    // buildWhole computes its leaves' boxes from the vertices, inflated: the same pairs as a tree over every
    // triangle's triangleBounds box must give (brute force), on any number of workers, with the order as its leaves.
    // Random triangles near the sphere's surface meet it, some only through the inflation.
    TriangleMesh sphere = scenes::makeSphere(1.0, 90, 45);
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> jitter(-0.002, 0.002);
    for (Vec3& v : sphere.vertices) v += Vec3(jitter(rng), jitter(rng), jitter(rng));
    constexpr double kInflate = 0.01;
    std::vector<Aabb> sphereBoxes(sphere.triangles.size()), sphereTight(sphere.triangles.size());
    for (std::uint32_t t = 0; t < sphere.triangles.size(); ++t) {
        sphereBoxes[t] = triangleBounds(sphere, t, kInflate);
        sphereTight[t] = triangleBounds(sphere, t);
    }
    std::vector<Aabb> soup(3000);
    std::normal_distribution<double> gauss;
    for (Aabb& box : soup) {
        const Vec3 at = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized() * (1.0 + 0.03 * gauss(rng));
        box = {at, at + Vec3::Constant(0.004)};
    }
    std::vector<std::uint32_t> all(sphere.triangles.size()), allSoup(soup.size());
    std::iota(all.begin(), all.end(), 0u);
    std::iota(allSoup.begin(), allSoup.end(), 0u);
    const auto expected = bruteForce(sphereBoxes, all, soup, allSoup);
    ASSERT_GT(expected.size(), bruteForce(sphereTight, all, soup, allSoup).size()) << "pairs only the inflation makes";
    std::vector<std::uint32_t> order;
    spatialOrder(sphere, order);
    BoxTree soupTree;
    soupTree.build(soup, allSoup);
    TaskPool three(3);
    for (TaskPool* pool : {static_cast<TaskPool*>(nullptr), &three}) {
        BoxTree whole;
        whole.buildWhole(sphere, order, kInflate, pool);
        EXPECT_EQ(whole.leafTriangles(), order);
        for (const std::size_t target : {1u, 64u, 4096u}) {
            std::vector<BoxTree::NodePair> frontier, stack;
            BoxTree::split(whole, soupTree, target, frontier);
            std::vector<TrianglePair> got;
            for (const BoxTree::NodePair& p : frontier) BoxTree::leafPairs(whole, soupTree, p, stack, got);
            std::sort(got.begin(), got.end());
            EXPECT_EQ(got, expected) << "target " << target;
        }
        std::vector<BoxTree::NodePair> stack;
        EXPECT_TRUE(whole.anyOverlap(soup[expected.front().b], stack));
        EXPECT_FALSE(whole.anyOverlap(Aabb{Vec3::Constant(-0.1), Vec3::Constant(0.1)}, stack)) << "inside the shell";
    }
}

}  // namespace
}  // namespace cullide
