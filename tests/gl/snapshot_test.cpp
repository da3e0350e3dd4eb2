// The snapshot renderer on llvmpipe: real content (colours where the objects are, background elsewhere, image
// orientation), highlight / mark / fade rules, robustness to bad input, PNG round trip, determinism, and that it
// lives beside the culler without changing its results.
#include "Compare.h"
#include "GlTestSupport.h"

#include "cullide/io/Image.h"
#include "cullide/scenes/Procedural.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide::test {
namespace {

using Rgba = std::array<int, 4>;

Rgba at(const Image& image, int x, int y) {
    const std::size_t i = 4 * (static_cast<std::size_t>(y) * image.width + x);
    return {image.rgba[i], image.rgba[i + 1], image.rgba[i + 2], image.rgba[i + 3]};
}

Rgba centre(const Image& image) { return at(image, image.width / 2, image.height / 2); }

Rgba bytes(const std::array<float, 3>& c) {
    return {static_cast<int>(std::lround(c[0] * 255)), static_cast<int>(std::lround(c[1] * 255)),
            static_cast<int>(std::lround(c[2] * 255)), 255};
}

/// True when the pixel is a shade of `colour` (shading only scales it): each channel's ratio to the largest one
/// matches the colour's within `tolerance`.
::testing::AssertionResult isShadeOf(const Rgba& pixel, const std::array<float, 3>& colour, double tolerance = 0.06) {
    const double pMax = std::max({pixel[0], pixel[1], pixel[2]});
    const double cMax = std::max({colour[0], colour[1], colour[2]});
    if (pMax < 30) return ::testing::AssertionFailure() << "pixel too dark to judge";
    for (int c = 0; c < 3; ++c) {
        if (std::abs(pixel[c] / pMax - colour[c] / cMax) > tolerance)
            return ::testing::AssertionFailure() << "pixel (" << pixel[0] << ", " << pixel[1] << ", " << pixel[2]
                                                 << ") is not a shade of (" << colour[0] << ", " << colour[1] << ", "
                                                 << colour[2] << ")";
    }
    return ::testing::AssertionSuccess();
}

/// Bounding rectangle of the pixels that differ from `background`: {x0, y0, x1, y1} (inclusive), or x0 = -1.
std::array<int, 4> contentBounds(const Image& image, const Rgba& background) {
    std::array<int, 4> r{-1, -1, -1, -1};
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            if (at(image, x, y) == background) continue;
            if (r[0] < 0) r = {x, y, x, y};
            r = {std::min(r[0], x), std::min(r[1], y), std::max(r[2], x), std::max(r[3], y)};
        }
    }
    return r;
}

std::size_t differingPixels(const Image& a, const Image& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.rgba.size(); i += 4)
        n += a.rgba[i] != b.rgba[i] || a.rgba[i + 1] != b.rgba[i + 1] || a.rgba[i + 2] != b.rgba[i + 2];
    return n;
}

std::vector<std::uint32_t> allTriangles(const TriangleMesh& mesh) {
    std::vector<std::uint32_t> all(mesh.triangles.size());
    std::iota(all.begin(), all.end(), 0u);
    return all;
}

const std::array<float, 3> kRed{1.0f, 0.0f, 0.0f};
const Rgba kWhite{255, 255, 255, 255};

TEST(Snapshot, BoxIsDrawnAtTheCentreOnTheBackground) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    EXPECT_FALSE(renderer->renderer().empty());
    const TriangleMesh box = scenes::makeBox(Vec3(1, 1, 1));
    const Image image = renderer->render({{&box, kRed, nullptr, nullptr}}, SnapshotView{});
    ASSERT_EQ(image.width, 640);
    ASSERT_EQ(image.height, 480);
    ASSERT_EQ(image.rgba.size(), 640u * 480u * 4u);
    const Rgba c = centre(image);
    EXPECT_GT(c[0], 60) << "centre " << c[0] << "," << c[1] << "," << c[2];
    EXPECT_LT(c[1], 10);
    EXPECT_LT(c[2], 10);
    EXPECT_EQ(c[3], 255);
    for (auto [x, y] : {std::pair{0, 0}, std::pair{639, 0}, std::pair{0, 479}, std::pair{639, 479}})
        EXPECT_EQ(at(image, x, y), kWhite) << x << "," << y;
    // The frame (the box) is fitted: centred, filling ~94% of the image's height (the limiting direction for a box
    // seen from 25 degrees up at 4:3).
    const auto b = contentBounds(image, kWhite);
    ASSERT_GE(b[0], 0);
    EXPECT_NEAR(0.5 * (b[0] + b[2]), 319.5, 2.0);
    EXPECT_NEAR(0.5 * (b[1] + b[3]), 239.5, 2.0);
    EXPECT_GT(b[3] - b[1] + 1, 0.9 * 480);
    EXPECT_LT(b[3] - b[1] + 1, 0.97 * 480);
    // Every pixel is a shade of red, or red blended with the background at the rim (multisampling): green and
    // blue stay equal; lit from both sides with ambient, no pixel of a face is near black.
    std::size_t dark = 0;
    for (int y = b[1]; y <= b[3]; ++y)
        for (int x = b[0]; x <= b[2]; ++x) {
            const Rgba p = at(image, x, y);
            ASSERT_EQ(p[1], p[2]) << x << "," << y;
            dark += p[0] < 40;
        }
    EXPECT_EQ(dark, 0u);
}

TEST(Snapshot, OrientationIsYUpAndRowZeroIsTheTop) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    // Seen from +z (azimuth 0, elevation 0): +x is right, +y is up.
    TriangleMesh right = scenes::makeBox(Vec3(0.4, 0.4, 0.4));
    TriangleMesh top = right;
    TriangleMesh left = right;
    for (auto& v : right.vertices) v.x() += 2;
    for (auto& v : left.vertices) v.x() -= 2;
    for (auto& v : top.vertices) v.y() += 2;
    SnapshotView view;
    view.azimuthDeg = 0;
    view.elevationDeg = 0;
    view.width = 300;
    view.height = 300;
    const std::array<float, 3> green{0, 1, 0}, blue{0, 0, 1};
    const Image image = renderer->render({{&right, kRed}, {&top, green}, {&left, blue}}, view);
    // The scene spans x in [-2.4, 2.4] and y in [-0.4, 2.4]: the top box is at the top centre.
    const int mid = 150;
    const double scale = 300 / (4.8 * 1.06);  // pixels per unit
    const int yCentre = 150;                   // the row of the scene's y centre, y = 1
    EXPECT_TRUE(isShadeOf(at(image, static_cast<int>(mid + 2 * scale), static_cast<int>(yCentre + 1 * scale)),
                          kRed));
    EXPECT_TRUE(isShadeOf(at(image, static_cast<int>(mid - 2 * scale), static_cast<int>(yCentre + 1 * scale)),
                          blue));
    EXPECT_TRUE(isShadeOf(at(image, mid, static_cast<int>(yCentre - 1 * scale)), green));
    EXPECT_EQ(at(image, mid, static_cast<int>(yCentre + 1 * scale)), kWhite);
}

// The depth test decides what shows, not the draw order: the box drawn with its triangles in reverse order gives
// the same image, up to a few pixels along edges where two faces meet at equal depth.
TEST(Snapshot, DrawOrderDoesNotChangeTheImage) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const TriangleMesh box = scenes::makeBox(Vec3(1, 1, 1));
    TriangleMesh reversed = box;
    std::reverse(reversed.triangles.begin(), reversed.triangles.end());
    SnapshotView view;
    const Image forward = renderer->render({{&box, kRed}}, view);
    const Image backward = renderer->render({{&reversed, kRed}}, view);
    const std::size_t boxPixels = differingPixels(forward, renderer->render({}, view));
    ASSERT_GT(boxPixels, 1000u);
    EXPECT_LT(differingPixels(forward, backward), boxPixels / 50) << "of " << boxPixels << " box pixels";
}

TEST(Snapshot, HighlightedAndMarkedTrianglesChangeColour) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const TriangleMesh box = scenes::makeBox(Vec3(1, 1, 1));
    const std::vector<std::uint32_t> all = allTriangles(box);
    const std::vector<std::uint32_t> none;
    SnapshotView view;
    const Image base = renderer->render({{&box, kRed, nullptr, nullptr}}, view);

    const Image highlighted = renderer->render({{&box, kRed, &all, nullptr}}, view);
    EXPECT_TRUE(isShadeOf(centre(highlighted), view.highlight));
    const Image marked = renderer->render({{&box, kRed, &all, &all}}, view);  // mark wins over highlight
    EXPECT_TRUE(isShadeOf(centre(marked), view.mark));
    const Image markedOnly = renderer->render({{&box, kRed, nullptr, &all}}, view);
    EXPECT_EQ(markedOnly.rgba, marked.rgba);

    // Two triangles (one face) highlighted: some of the box's pixels change, not all. The +z face: the default
    // view looks at the box from +x, +y, +z: the -z face (triangles 0 and 1) is hidden, and on the H100 changed no
    // pixel (llvmpipe showed a few where its edges tie in depth with the visible faces').
    const std::vector<std::uint32_t> face{2, 3};
    const std::size_t boxPixels = differingPixels(base, renderer->render({}, view));
    const Image partly = renderer->render({{&box, kRed, &face, nullptr}}, view);
    view.dimUnhighlighted = false;
    const Image partlyNoDim = renderer->render({{&box, kRed, &face, nullptr}}, view);
    const std::size_t changed = differingPixels(base, partlyNoDim);
    EXPECT_GT(changed, 0u);
    EXPECT_LT(changed, boxPixels);
    // With fading, every non-highlighted pixel of the box moves toward the background as well.
    EXPECT_GT(differingPixels(base, partly), changed);

    // An object with an empty highlight list is faded whole: lighter, still reddish. Not faded when turned off.
    view.dimUnhighlighted = true;
    const Image faded = renderer->render({{&box, kRed, &none, nullptr}}, view);
    const Rgba f = centre(faded);
    EXPECT_GT(f[1], 150);
    EXPECT_GT(f[0], f[1] + 20);
    EXPECT_EQ(f[1], f[2]);
    view.dimUnhighlighted = false;
    EXPECT_EQ(renderer->render({{&box, kRed, &none, nullptr}}, view).rgba, base.rgba);
}

TEST(Snapshot, EmptySceneIsPureBackground) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    SnapshotView view;
    view.width = 31;
    view.height = 17;
    view.background = {0.2f, 0.4f, 0.6f};
    const Rgba bg = bytes(view.background);
    const TriangleMesh empty;
    TriangleMesh allBad;
    allBad.vertices = {{0, 0, 0}, {1, 0, 0}, {0, std::numeric_limits<double>::quiet_NaN(), 0}};
    allBad.triangles = {{0, 1, 2}, {0, 1, 7}};
    for (const std::vector<SnapshotItem>& items :
         {std::vector<SnapshotItem>{}, std::vector<SnapshotItem>{{&empty}}, std::vector<SnapshotItem>{{&allBad}}}) {
        const Image image = renderer->render(items, view);
        ASSERT_EQ(image.rgba.size(), 31u * 17u * 4u);
        for (int y = 0; y < image.height; ++y)
            for (int x = 0; x < image.width; ++x) ASSERT_EQ(at(image, x, y), bg) << x << "," << y;
    }
    // An explicit frame around nothing is background too.
    Aabb frame;
    frame.grow(Vec3(-1, -1, -1));
    frame.grow(Vec3(1, 1, 1));
    view.frame = frame;
    const Image framed = renderer->render({}, view);
    EXPECT_EQ(contentBounds(framed, bg)[0], -1);
}

TEST(Snapshot, BadTrianglesAreSkippedAndTheRestRenders) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const TriangleMesh box = scenes::makeBox(Vec3(1, 1, 1));
    TriangleMesh bad = box;
    const std::uint32_t n = static_cast<std::uint32_t>(bad.vertices.size());
    bad.vertices.push_back(Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0));
    bad.vertices.push_back(Vec3(0, std::numeric_limits<double>::infinity(), 0));
    bad.triangles.push_back({0, 1, n});          // NaN vertex
    bad.triangles.push_back({n + 1, 2, 3});      // infinite vertex
    bad.triangles.push_back({0, 1, 1000000});    // index out of range
    bad.triangles.push_back({0xFFFFFFFFu, 0, 1});
    // Triangle 2 is on the +z face, which the default view sees; out-of-range entries are ignored.
    const std::vector<std::uint32_t> highlights{2, 13, 14, 999999, 0xFFFFFFFFu};
    const std::vector<std::uint32_t> boxHighlights{2};
    SnapshotView view;
    const Image expected = renderer->render({{&box, kRed, &boxHighlights, nullptr}}, view);
    const Image got = renderer->render({{&bad, kRed, &highlights, &highlights}}, view);
    const Image expectedMarked = renderer->render({{&box, kRed, &boxHighlights, &boxHighlights}}, view);
    EXPECT_EQ(got.rgba, expectedMarked.rgba);
    EXPECT_NE(expected.rgba, expectedMarked.rgba);

    // Finite doubles that overflow float (relative to the frame): skipped, no crash, the box still shows.
    TriangleMesh far = box;
    const std::uint32_t m = static_cast<std::uint32_t>(far.vertices.size());
    far.vertices.push_back(Vec3(1e300, 0, 0));
    far.triangles.push_back({0, 1, m});
    view.frame = scenes::boundsOf(box);
    const Image framedBox = renderer->render({{&box, kRed}}, view);
    EXPECT_EQ(renderer->render({{&far, kRed}}, view).rgba, framedBox.rgba);
    EXPECT_GT(centre(framedBox)[0], 60);
}

TEST(Snapshot, InvalidArgumentsThrow) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const TriangleMesh box = scenes::makeBox(Vec3(1, 1, 1));
    const std::vector<SnapshotItem> items{{&box}};
    auto withView = [&](auto change) {
        SnapshotView v;
        change(v);
        return v;
    };
    EXPECT_THROW(renderer->render({{nullptr}}, SnapshotView{}), std::invalid_argument);
    EXPECT_THROW(renderer->render({{&box}, {nullptr}}, SnapshotView{}), std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) { v.width = 0; })), std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) { v.height = -5; })), std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) { v.width = 8193; })), std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) {
                     v.azimuthDeg = std::numeric_limits<double>::quiet_NaN();
                 })),
                 std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) {
                     v.elevationDeg = std::numeric_limits<double>::infinity();
                 })),
                 std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) { v.frame = Aabb{}; })),
                 std::invalid_argument);  // empty
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) {
                     Aabb b;
                     b.grow(Vec3(0, 0, 0));
                     b.max.x() = std::numeric_limits<double>::infinity();
                     v.frame = b;
                 })),
                 std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) { v.background[1] = 1.5f; })),
                 std::invalid_argument);
    EXPECT_THROW(renderer->render(items, withView([](SnapshotView& v) {
                     v.mark[0] = std::numeric_limits<float>::quiet_NaN();
                 })),
                 std::invalid_argument);
    EXPECT_THROW(renderer->render({{&box, {0.5f, -0.1f, 0.5f}}}, SnapshotView{}), std::invalid_argument);
    // Still usable afterwards.
    EXPECT_GT(centre(renderer->render(items, SnapshotView{}))[0], 60);
}

TEST(Snapshot, SizesAnglesAndFlatFrames) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const TriangleMesh box = scenes::makeBox(Vec3(1, 2, 3));
    for (auto [w, h] : {std::pair{1, 1}, std::pair{300, 100}, std::pair{100, 300}, std::pair{4500, 8}}) {
        SnapshotView view;
        view.width = w;
        view.height = h;
        const Image image = renderer->render({{&box, kRed}}, view);
        ASSERT_EQ(image.width, w);
        ASSERT_EQ(image.height, h);
        ASSERT_EQ(image.rgba.size(), 4u * w * h);
        EXPECT_GT(centre(image)[0], 60) << w << "x" << h;
    }
    // Straight down, straight up and beyond: always a valid camera.
    for (double elevation : {90.0, -90.0, 135.0, 0.0}) {
        SnapshotView view;
        view.elevationDeg = elevation;
        view.azimuthDeg = 720 + 10;
        const Image image = renderer->render({{&box, kRed}}, view);
        EXPECT_GT(centre(image)[0], 60) << elevation;
        EXPECT_EQ(at(image, 0, 0), kWhite) << elevation;
    }
    // A single flat triangle seen exactly edge-on, and a point-sized one: no crash, background at the corners.
    TriangleMesh flat;
    flat.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
    flat.triangles = {{0, 1, 2}};
    TriangleMesh point;
    point.vertices = {{5, 5, 5}, {5, 5, 5}, {5, 5, 5}};
    point.triangles = {{0, 1, 2}};
    SnapshotView side;
    side.elevationDeg = 0;
    for (const TriangleMesh* mesh : {&flat, &point}) {
        const Image image = renderer->render({{mesh, kRed}}, side);
        EXPECT_EQ(at(image, 0, 0), kWhite);
    }
}

TEST(Snapshot, LargeImagesWithoutMultisampling) {
    // Above 4096² pixels the renderer draws single-sampled (memory): the other path, same content rules.
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const TriangleMesh box = scenes::makeBox(Vec3(1, 1, 1));
    SnapshotView view;
    view.width = 8192;
    view.height = 2100;
    const Image image = renderer->render({{&box, kRed}}, view);
    ASSERT_EQ(image.rgba.size(), 4u * 8192u * 2100u);
    EXPECT_GT(centre(image)[0], 60);
    EXPECT_LT(centre(image)[1], 10);
    EXPECT_EQ(at(image, 0, 0), kWhite);
    EXPECT_EQ(at(image, 8191, 2099), kWhite);
    // Back to a small image: multisampled again, the same bytes as a fresh renderer's.
    const Image small = renderer->render({{&box, kRed}}, SnapshotView{});
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(fresh);
    EXPECT_EQ(fresh->render({{&box, kRed}}, SnapshotView{}).rgba, small.rgba);
}

TEST(Snapshot, PngRoundTripAndDeterminism) {
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    TriangleMesh torus = scenes::makeTorus(1.0, 0.3, 48, 24);
    TriangleMesh sphere = scenes::makeSphere(0.6, 32, 16);
    for (auto& v : sphere.vertices) v.x() += 1.0;
    const std::vector<std::uint32_t> pcs{0, 5, 17, 200, 201, 202, 1000};
    const std::vector<std::uint32_t> hits{17, 201};
    const std::vector<SnapshotItem> items{{&torus, {0.3f, 0.5f, 0.9f}, &pcs, &hits}, {&sphere, {0.2f, 0.7f, 0.3f}}};
    SnapshotView view;
    const Image first = renderer->render(items, view);
    const Image second = renderer->render(items, view);
    EXPECT_EQ(first.rgba, second.rgba);
    // After a render at another size (the targets are recreated) the bytes are still the same.
    SnapshotView other = view;
    other.width = 123;
    (void)renderer->render(items, other);
    EXPECT_EQ(renderer->render(items, view).rgba, first.rgba);
    // ...and from a second renderer.
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(another);
    EXPECT_EQ(another->render(items, view).rgba, first.rgba);

    const std::string path = (std::filesystem::temp_directory_path() /
                              ("cullide_snapshot_" + std::to_string(::getpid()) + ".png"))
                                 .string();
    io::writePng(path, first);
    const Image back = io::readPng(path);
    std::filesystem::remove(path);
    EXPECT_EQ(back.width, first.width);
    EXPECT_EQ(back.height, first.height);
    EXPECT_EQ(back.rgba, first.rgba);
}

TEST(Snapshot, LivesBesideTheCullerWithoutChangingIt) {
    Settings settings;
    settings.gpuLevels = GpuLevels::Always;  // the culler's GL work runs before and after the renderer's
    settings.exactThreshold = 0;
    CULLIDE_GPU_CULLER_OR_SKIP(culler, settings);
    CULLIDE_SNAPSHOT_RENDERER_OR_SKIP(renderer);
    const auto meshes = randomSoups(3, 8, 60, 0.25);
    const auto objects = asObjects(meshes);
    Result before, after;
    culler->run(objects, before);
    std::vector<SnapshotItem> items;
    std::vector<std::vector<std::uint32_t>> marked(meshes.size());
    for (const ObjectPair& pair : before.pairs)
        for (const TrianglePair& t : pair.triangles) {
            marked[pair.a].push_back(t.a);
            marked[pair.b].push_back(t.b);
        }
    for (std::size_t i = 0; i < meshes.size(); ++i)
        items.push_back({&meshes[i], {0.6f, 0.6f, 0.7f}, &before.pcsTriangles[i], &marked[i]});
    const Image image = renderer->render(items, SnapshotView{});
    culler->run(objects, after);
    const Comparison cmp = compare(before, after);
    EXPECT_EQ(cmp.missed, 0u);
    EXPECT_EQ(cmp.spurious, 0u);
    EXPECT_TRUE(cmp.objectPairsEqual);
    EXPECT_EQ(before.pcsTriangles, after.pcsTriangles);
    // Something was drawn in the mark colour when there are intersecting pairs.
    if (!before.pairs.empty()) {
        bool sawMark = false;
        for (int y = 0; y < image.height && !sawMark; ++y)
            for (int x = 0; x < image.width && !sawMark; ++x) {
                const Rgba p = at(image, x, y);
                sawMark = p[0] > 60 && p[1] < p[0] / 3 && p[2] < p[0] / 3;
            }
        EXPECT_TRUE(sawMark);
    }
}

}  // namespace
}  // namespace cullide::test
