// PNG reading and writing (Image.h): exact round trips, every colour type libpng converts, and every kind of broken
// file (missing, empty, truncated at each length, garbage, a header larger than its file) failing with a message
// that names the path.
#include "ImageSupport.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace cullide::io {
namespace {

using namespace cullide::test;

namespace fs = std::filesystem;

// Small PNGs made by hand (zlib + CRC) for the colour types our writer never produces.
// 2x2 grey 8-bit: 0, 85 / 170, 255.
const unsigned char kGrey8[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x00, 0x00, 0x00, 0x00, 0x57, 0xdd, 0x52,
    0xf8, 0x00, 0x00, 0x00, 0x0e, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x08, 0x65, 0x58,
    0xf5, 0x1f, 0x00, 0x03, 0xad, 0x01, 0xff, 0x67, 0xfb, 0xca, 0x09, 0x00, 0x00, 0x00, 0x00, 0x49,
    0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
// 3x1 grey 1-bit: white, black, white.
const unsigned char kGrey1[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00, 0x33, 0x9b, 0x29,
    0x19, 0x00, 0x00, 0x00, 0x0a, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x58, 0x00, 0x00, 0x00,
    0xa2, 0x00, 0xa1, 0xdc, 0x8d, 0xb1, 0xcc, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae,
    0x42, 0x60, 0x82,
};
// 2x1 palette (10,20,30), (40,50,60) with tRNS alpha 128 for entry 0.
const unsigned char kPaletteTrns[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x01, 0x08, 0x03, 0x00, 0x00, 0x00, 0xc3, 0xfc, 0x8f,
    0xb8, 0x00, 0x00, 0x00, 0x06, 0x50, 0x4c, 0x54, 0x45, 0x0a, 0x14, 0x1e, 0x28, 0x32, 0x3c, 0xd5,
    0x1b, 0xb4, 0xe9, 0x00, 0x00, 0x00, 0x01, 0x74, 0x52, 0x4e, 0x53, 0x80, 0xad, 0x5e, 0x5b, 0x46,
    0x00, 0x00, 0x00, 0x0b, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x60, 0x04, 0x00, 0x00,
    0x04, 0x00, 0x02, 0xbf, 0x7a, 0x3f, 0x4a, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae,
    0x42, 0x60, 0x82,
};
// 1x1 RGB 16-bit: 0x1234, 0x8080, 0xffff.
const unsigned char kRgb16[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x10, 0x02, 0x00, 0x00, 0x00, 0xc0, 0xe7, 0x8f,
    0x9d, 0x00, 0x00, 0x00, 0x0f, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x10, 0x32, 0x69, 0x68,
    0xf8, 0xff, 0x1f, 0x00, 0x07, 0xf4, 0x03, 0x45, 0x73, 0xd8, 0x34, 0x7f, 0x00, 0x00, 0x00, 0x00,
    0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
// 1x1 grey + alpha 8-bit: 200, alpha 100.
const unsigned char kGreyAlpha8[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x08, 0x04, 0x00, 0x00, 0x00, 0xb5, 0x1c, 0x0c,
    0x02, 0x00, 0x00, 0x00, 0x0b, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x38, 0x91, 0x02, 0x00,
    0x01, 0xf7, 0x01, 0x2d, 0x90, 0x1d, 0xa3, 0xbd, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44,
    0xae, 0x42, 0x60, 0x82,
};
// 3x3 RGB 8-bit, Adam7 interlaced: pixel (x, y) = (10x + 1, 10y + 2, 50).
const unsigned char kInterlacedRgb[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x03, 0x08, 0x02, 0x00, 0x00, 0x01, 0xae, 0x4d, 0x12,
    0x7e, 0x00, 0x00, 0x00, 0x25, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x64, 0x32, 0x62,
    0x10, 0x05, 0x62, 0x46, 0x31, 0x23, 0x51, 0x31, 0x23, 0x06, 0x6e, 0x20, 0x93, 0x1b, 0x48, 0x33,
    0xf2, 0x18, 0x71, 0xf3, 0x18, 0x89, 0xf2, 0x18, 0x01, 0x00, 0x26, 0x92, 0x02, 0x92, 0x81, 0xb6,
    0xba, 0x4f, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82,
};
// A valid 60000x60000 RGBA header (14 GB decoded) in a 68-byte file.
const unsigned char kHugeHeader[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52,
    0x00, 0x00, 0xea, 0x60, 0x00, 0x00, 0xea, 0x60, 0x08, 0x06, 0x00, 0x00, 0x00, 0x80, 0xd2, 0x75,
    0x42, 0x00, 0x00, 0x00, 0x0b, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60, 0x80, 0x01, 0x00,
    0x00, 0x0a, 0x00, 0x01, 0x7f, 0x80, 0x74, 0x5e, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44,
    0xae, 0x42, 0x60, 0x82,
};

/// A fresh temporary directory per test, removed afterwards.
class TempDir {
public:
    TempDir() {
        static int counter = 0;
        m_path = fs::temp_directory_path() /
                 ("cullide_image_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        fs::remove_all(m_path);
        fs::create_directories(m_path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    std::string file(const std::string& name) const { return (m_path / name).string(); }
    std::string write(const std::string& name, const std::vector<std::uint8_t>& bytes) const {
        const std::string p = file(name);
        std::ofstream out(p, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        return p;
    }
    template <std::size_t N>
    std::string write(const std::string& name, const unsigned char (&bytes)[N]) const {
        return write(name, std::vector<std::uint8_t>(bytes, bytes + N));
    }

private:
    fs::path m_path;
};

std::vector<std::uint8_t> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Expects readPng(path) to throw std::runtime_error whose message names the path.
::testing::AssertionResult readFailsNaming(const std::string& path) {
    try {
        (void)readPng(path);
    } catch (const std::runtime_error& e) {
        if (std::string(e.what()).find(path) == std::string::npos)
            return ::testing::AssertionFailure() << "message does not name the path: " << e.what();
        return ::testing::AssertionSuccess();
    } catch (const std::exception& e) {
        return ::testing::AssertionFailure() << "wrong exception type: " << e.what();
    }
    return ::testing::AssertionFailure() << "no exception for " << path;
}

// ---------------------------------------------------------------------------------------------------------------
// PNG

TEST(Png, RoundTripIsExact) {
    TempDir dir;
    for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 5}, std::pair{640, 3}, std::pair{3, 300}}) {
        const Image image = pattern(w, h, static_cast<std::uint32_t>(w * 1000 + h));
        const std::string path = dir.file("round.png");
        writePng(path, image);
        const Image back = readPng(path);
        EXPECT_EQ(back.width, w);
        EXPECT_EQ(back.height, h);
        EXPECT_EQ(back.rgba, image.rgba) << w << "x" << h;
    }
}

TEST(Png, OverwritesAnExistingFile) {
    TempDir dir;
    const std::string path = dir.file("twice.png");
    writePng(path, pattern(64, 64, 1));
    const Image small = pattern(2, 3, 2);
    writePng(path, small);
    EXPECT_EQ(readPng(path).rgba, small.rgba);
}

TEST(Png, ReadsEveryColourTypeAsRgba8) {
    TempDir dir;
    {
        const Image i = readPng(dir.write("grey8.png", kGrey8));
        ASSERT_EQ(i.width, 2);
        ASSERT_EQ(i.height, 2);
        EXPECT_EQ(pixel(i, 0, 0), (Rgba{0, 0, 0, 255}));
        EXPECT_EQ(pixel(i, 1, 0), (Rgba{85, 85, 85, 255}));
        EXPECT_EQ(pixel(i, 0, 1), (Rgba{170, 170, 170, 255}));
        EXPECT_EQ(pixel(i, 1, 1), (Rgba{255, 255, 255, 255}));
    }
    {
        const Image i = readPng(dir.write("grey1.png", kGrey1));
        ASSERT_EQ(i.width, 3);
        ASSERT_EQ(i.height, 1);
        EXPECT_EQ(pixel(i, 0, 0), (Rgba{255, 255, 255, 255}));
        EXPECT_EQ(pixel(i, 1, 0), (Rgba{0, 0, 0, 255}));
        EXPECT_EQ(pixel(i, 2, 0), (Rgba{255, 255, 255, 255}));
    }
    {
        const Image i = readPng(dir.write("palette.png", kPaletteTrns));
        ASSERT_EQ(i.width, 2);
        EXPECT_EQ(pixel(i, 0, 0), (Rgba{10, 20, 30, 128}));
        EXPECT_EQ(pixel(i, 1, 0), (Rgba{40, 50, 60, 255}));
    }
    {
        const Image i = readPng(dir.write("rgb16.png", kRgb16));
        ASSERT_EQ(i.rgba.size(), 4u);
        EXPECT_EQ(pixel(i, 0, 0), (Rgba{18, 128, 255, 255}));  // scaled with rounding
    }
    {
        const Image i = readPng(dir.write("greyalpha.png", kGreyAlpha8));
        EXPECT_EQ(pixel(i, 0, 0), (Rgba{200, 200, 200, 100}));
    }
    {
        const Image i = readPng(dir.write("interlaced.png", kInterlacedRgb));
        ASSERT_EQ(i.width, 3);
        ASSERT_EQ(i.height, 3);
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 3; ++x)
                EXPECT_EQ(pixel(i, x, y), (Rgba{static_cast<std::uint8_t>(10 * x + 1),
                                                static_cast<std::uint8_t>(10 * y + 2), 50, 255}))
                    << x << "," << y;
    }
}

TEST(Png, MissingEmptyAndDirectoryFail) {
    TempDir dir;
    EXPECT_TRUE(readFailsNaming(dir.file("does_not_exist.png")));
    EXPECT_TRUE(readFailsNaming(dir.write("empty.png", std::vector<std::uint8_t>{})));
    EXPECT_TRUE(readFailsNaming(dir.file("")));  // the directory itself
}

TEST(Png, EveryTruncationFails) {
    TempDir dir;
    const std::string full = dir.file("full.png");
    writePng(full, pattern(13, 9));
    const std::vector<std::uint8_t> bytes = readBytes(full);
    ASSERT_GT(bytes.size(), 60u);
    for (std::size_t n = 0; n < bytes.size(); ++n) {
        const std::string path =
            dir.write("cut.png", std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(n)));
        EXPECT_TRUE(readFailsNaming(path)) << "truncated to " << n << " of " << bytes.size() << " bytes";
    }
    for (const unsigned char* vector : {kGrey8, kInterlacedRgb}) {
        const std::size_t size = vector == kGrey8 ? sizeof kGrey8 : sizeof kInterlacedRgb;
        for (std::size_t n = 0; n < size; ++n) {
            const std::string path = dir.write("cut2.png", std::vector<std::uint8_t>(vector, vector + n));
            EXPECT_TRUE(readFailsNaming(path)) << n;
        }
    }
}

TEST(Png, GarbageFails) {
    TempDir dir;
    std::mt19937 rng(7);
    for (int round = 0; round < 50; ++round) {
        std::vector<std::uint8_t> bytes(static_cast<std::size_t>(1 + rng() % 400));
        for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
        if (round % 2 == 1) {  // a valid signature, garbage after it
            const std::uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
            bytes.insert(bytes.begin(), signature, signature + 8);
        }
        EXPECT_TRUE(readFailsNaming(dir.write("garbage.png", bytes))) << "round " << round;
    }
    const std::string text = dir.write("text.png", std::vector<std::uint8_t>{'h', 'e', 'l', 'l', 'o', '\n'});
    EXPECT_TRUE(readFailsNaming(text));
}

TEST(Png, CorruptedBytesNeverCrash) {
    // Flipping any byte of a valid file either fails cleanly or (a byte libpng does not check) decodes to an image
    // of consistent size.
    TempDir dir;
    const std::string full = dir.file("full.png");
    writePng(full, pattern(11, 7));
    const std::vector<std::uint8_t> bytes = readBytes(full);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        std::vector<std::uint8_t> bad = bytes;
        bad[i] ^= static_cast<std::uint8_t>(0x5a);
        const std::string path = dir.write("bad.png", bad);
        try {
            const Image image = readPng(path);
            EXPECT_EQ(image.rgba.size(), 4u * static_cast<std::size_t>(image.width) * image.height);
        } catch (const std::runtime_error& e) {
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    }
}

TEST(Png, HeaderLargerThanTheFileFailsWithoutAllocating) {
    TempDir dir;
    const std::string path = dir.write("huge.png", kHugeHeader);
    EXPECT_TRUE(readFailsNaming(path));
    try {
        (void)readPng(path);
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("larger than the file"), std::string::npos) << e.what();
    }
}

TEST(Png, WriteErrorsNameThePath) {
    TempDir dir;
    const std::string path = dir.file("no_such_dir/out.png");
    try {
        writePng(path, pattern(2, 2));
        ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
    if (fs::exists("/dev/full")) {  // ENOSPC on every write: found when the buffer is flushed
        try {
            writePng("/dev/full", pattern(64, 64));
            ADD_FAILURE() << "no exception writing to /dev/full";
        } catch (const std::runtime_error& e) {
            EXPECT_NE(std::string(e.what()).find("/dev/full"), std::string::npos) << e.what();
        }
    }
}

TEST(Png, InvalidImagesAreRejected) {
    TempDir dir;
    const std::string path = dir.file("x.png");
    Image empty;
    EXPECT_THROW(writePng(path, empty), std::invalid_argument);
    Image wrong = pattern(4, 4);
    wrong.rgba.pop_back();
    EXPECT_THROW(writePng(path, wrong), std::invalid_argument);
    Image negative = pattern(1, 1);
    negative.width = -1;
    EXPECT_THROW(writePng(path, negative), std::invalid_argument);
    EXPECT_FALSE(fs::exists(path));
}

}  // namespace
}  // namespace cullide::io
