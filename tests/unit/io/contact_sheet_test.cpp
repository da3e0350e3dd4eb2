// Contact sheets (Image.h): equal sizes in a grid, different sizes centred in the largest cell, invalid arguments.
#include "ImageSupport.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace cullide::io {
namespace {

using namespace cullide::test;

// ---------------------------------------------------------------------------------------------------------------
// Contact sheets

TEST(ContactSheet, EqualSizesInAGrid) {
    const Rgba red{255, 0, 0, 255}, green{0, 255, 0, 255}, blue{0, 0, 255, 128};
    const std::vector<Image> images = {solid(2, 3, red), solid(2, 3, green), solid(2, 3, blue)};
    const Image sheet = makeContactSheet(images, 2, 1, {9, 8, 7});
    // 2 columns x 2 rows of 2x3 cells, 1-pixel borders.
    ASSERT_EQ(sheet.width, 2 * 2 + 3 * 1);
    ASSERT_EQ(sheet.height, 2 * 3 + 3 * 1);
    ASSERT_EQ(sheet.rgba.size(), 4u * sheet.width * sheet.height);
    const Rgba border{9, 8, 7, 255};
    for (int y = 0; y < sheet.height; ++y) {
        for (int x = 0; x < sheet.width; ++x) {
            Rgba expected = border;
            const bool col0 = x >= 1 && x < 3, col1 = x >= 4 && x < 6;
            const bool row0 = y >= 1 && y < 4, row1 = y >= 5 && y < 8;
            if (row0 && col0) expected = red;
            if (row0 && col1) expected = green;
            if (row1 && col0) expected = blue;  // alpha kept
            EXPECT_EQ(pixel(sheet, x, y), expected) << x << "," << y;
        }
    }
}

TEST(ContactSheet, DifferentSizesAreCentredInTheLargestCell) {
    const Rgba a{1, 1, 1, 255}, b{2, 2, 2, 255}, border{0, 0, 0, 255};
    const Image sheet = makeContactSheet({solid(4, 2, a), solid(2, 4, b)}, 5, 0, {0, 0, 0});
    ASSERT_EQ(sheet.width, 8);  // 2 columns (only 2 images) of 4
    ASSERT_EQ(sheet.height, 4);
    // Image a: rows 1-2 of cell 0; image b: columns 1-2 of cell 1.
    EXPECT_EQ(pixel(sheet, 0, 0), border);
    EXPECT_EQ(pixel(sheet, 0, 1), a);
    EXPECT_EQ(pixel(sheet, 3, 2), a);
    EXPECT_EQ(pixel(sheet, 3, 3), border);
    EXPECT_EQ(pixel(sheet, 4, 0), border);
    EXPECT_EQ(pixel(sheet, 5, 0), b);
    EXPECT_EQ(pixel(sheet, 6, 3), b);
    EXPECT_EQ(pixel(sheet, 7, 3), border);
    // Odd differences round toward the top left: a 1x1 in a 4x4 cell sits at (1, 1).
    const Image odd = makeContactSheet({solid(4, 4, a), solid(1, 1, b)}, 1, 0, {0, 0, 0});
    ASSERT_EQ(odd.height, 8);
    EXPECT_EQ(pixel(odd, 1, 5), b);
    EXPECT_EQ(pixel(odd, 2, 6), border);
}

TEST(ContactSheet, InvalidArguments) {
    const Image ok = solid(2, 2, {1, 2, 3, 4});
    EXPECT_THROW(makeContactSheet({}, 1), std::invalid_argument);
    EXPECT_THROW(makeContactSheet({ok}, 0), std::invalid_argument);
    EXPECT_THROW(makeContactSheet({ok}, -3), std::invalid_argument);
    EXPECT_THROW(makeContactSheet({ok}, 1, -1), std::invalid_argument);
    EXPECT_THROW(makeContactSheet({ok}, 1, 1025), std::invalid_argument);
    Image bad = ok;
    bad.rgba.resize(3);
    EXPECT_THROW(makeContactSheet({ok, bad}, 2), std::invalid_argument);
    // 70000 pixels wide: too large.
    EXPECT_THROW(makeContactSheet(std::vector<Image>(2, solid(35000, 1, {0, 0, 0, 0})), 2, 0),
                 std::invalid_argument);
}

}  // namespace
}  // namespace cullide::io
