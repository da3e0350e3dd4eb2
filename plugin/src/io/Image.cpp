// PNG reading and writing (libpng) and contact sheets.
//
// libpng reports errors by longjmp to a setjmp point. A longjmp must never skip a C++ destructor, so each of the
// two codec functions below (decodePng, encodePng) is written in C style: the setjmp is in that function, which
// holds no object with a destructor; every resource (libpng structs, the FILE, the pixel vector, the file's bytes)
// is owned by RAII objects in the caller's frame, which the longjmp never leaves. libpng's own allocations are
// released by png_destroy_*_struct on every path.
//
// Untrusted files: a PNG declares its size in IHDR before any pixel data. Before allocating for it, the size is
// checked against what the file can hold (deflate expands at most 1032:1), so a short garbage file cannot make us
// allocate gigabytes; rows of non-interlaced images are also allocated as they are decoded.
#include "cullide/io/Image.h"

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace cullide::io {
namespace {

constexpr std::uint64_t kMaxFileBytes = 1ull << 30;
constexpr std::uint64_t kMaxImageBytes = 1ull << 30;  // decoded RGBA8
constexpr png_uint_32 kMaxDimension = 1u << 16;
constexpr int kMaxSheetSize = 65535;
constexpr int kMaxBorder = 1024;

void requireValid(const Image& image, const std::string& what) {
    if (image.width < 1 || image.height < 1)
        throw std::invalid_argument(what + ": image size must be at least 1x1, got " + std::to_string(image.width) +
                                    "x" + std::to_string(image.height));
    const std::uint64_t expected =
        4ull * static_cast<std::uint64_t>(image.width) * static_cast<std::uint64_t>(image.height);
    if (image.rgba.size() != expected)
        throw std::invalid_argument(what + ": rgba holds " + std::to_string(image.rgba.size()) + " bytes, " +
                                    std::to_string(image.width) + "x" + std::to_string(image.height) + " needs " +
                                    std::to_string(expected));
}

std::string systemError() { return std::strerror(errno); }

// ---------------------------------------------------------------------------------------------------------------
// libpng glue

/// libpng's error pointer: the last error message (fixed size: it is written on the error path, just before the
/// longjmp, where nothing should allocate).
struct PngError {
    char message[256] = "unknown libpng error";
};

void onPngError(png_structp png, png_const_charp message) {
    auto* error = static_cast<PngError*>(png_get_error_ptr(png));
    if (error != nullptr) std::snprintf(error->message, sizeof error->message, "%s", message ? message : "?");
    png_longjmp(png, 1);
}

/// Warnings (a bad CRC in an ancillary chunk, an unknown chunk) do not make an image unusable.
void onPngWarning(png_structp, png_const_charp) {}

class PngReadStruct {
public:
    explicit PngReadStruct(PngError& error) {
        m_png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, onPngError, onPngWarning);
        if (m_png != nullptr) m_info = png_create_info_struct(m_png);
    }
    ~PngReadStruct() {
        if (m_png != nullptr) png_destroy_read_struct(&m_png, m_info != nullptr ? &m_info : nullptr, nullptr);
    }
    PngReadStruct(const PngReadStruct&) = delete;
    PngReadStruct& operator=(const PngReadStruct&) = delete;
    bool ok() const { return m_png != nullptr && m_info != nullptr; }
    png_structp png() const { return m_png; }
    png_infop info() const { return m_info; }

private:
    png_structp m_png = nullptr;
    png_infop m_info = nullptr;
};

class PngWriteStruct {
public:
    explicit PngWriteStruct(PngError& error) {
        m_png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, onPngError, onPngWarning);
        if (m_png != nullptr) m_info = png_create_info_struct(m_png);
    }
    ~PngWriteStruct() {
        if (m_png != nullptr) png_destroy_write_struct(&m_png, m_info != nullptr ? &m_info : nullptr);
    }
    PngWriteStruct(const PngWriteStruct&) = delete;
    PngWriteStruct& operator=(const PngWriteStruct&) = delete;
    bool ok() const { return m_png != nullptr && m_info != nullptr; }
    png_structp png() const { return m_png; }
    png_infop info() const { return m_info; }

private:
    png_structp m_png = nullptr;
    png_infop m_info = nullptr;
};

struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

/// The whole file in memory; libpng reads from it (a short read is a truncated file, reported by png_error).
struct MemoryInput {
    const std::uint8_t* data = nullptr;
    std::size_t size = 0;
    std::size_t offset = 0;
};

void readFromMemory(png_structp png, png_bytep out, png_size_t length) {
    auto* in = static_cast<MemoryInput*>(png_get_io_ptr(png));
    if (length > in->size - in->offset) png_error(png, "unexpected end of file (truncated)");
    std::memcpy(out, in->data + in->offset, length);
    in->offset += length;
}

/// What decodePng produces; owned by the caller.
struct Decoded {
    std::vector<std::uint8_t>* pixels = nullptr;  // RGBA8, rows top to bottom
    png_uint_32 width = 0;
    png_uint_32 height = 0;
};

/// All libpng calls of a read, between setjmp and libpng's longjmp: no destructors in this frame (see the top of
/// the file). Returns false after a libpng error (the message is in the struct's PngError).
bool decodePng(png_structp png, png_infop info, MemoryInput* input, Decoded* out) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_set_read_fn(png, input, readFromMemory);
    png_set_user_limits(png, kMaxDimension, kMaxDimension);
    png_read_info(png, info);
    png_uint_32 width = 0, height = 0;
    int bitDepth = 0, colourType = 0, interlace = 0;
    png_get_IHDR(png, info, &width, &height, &bitDepth, &colourType, &interlace, nullptr, nullptr);
    const std::uint64_t pixels = static_cast<std::uint64_t>(width) * height;
    // The file must be able to hold the image's data: at least pixels * bits per pixel compressed at most 1032:1.
    const std::uint64_t rawBits = pixels * png_get_channels(png, info) * static_cast<std::uint64_t>(bitDepth);
    if (rawBits / 8 > 1100 * static_cast<std::uint64_t>(input->size) + 4096)
        png_error(png, "image size in the header is larger than the file can hold");
    if (4 * pixels > kMaxImageBytes) png_error(png, "image larger than 1 GiB as RGBA");

    png_set_expand(png);    // palette -> RGB, grey below 8 bits -> 8 bits, tRNS -> alpha
    png_set_scale_16(png);  // 16 -> 8 bits, rounded
    png_set_gray_to_rgb(png);
    png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);  // only where there is no alpha channel
    const int passes = png_set_interlace_handling(png);
    png_read_update_info(png, info);
    const std::size_t rowBytes = png_get_rowbytes(png, info);
    if (png_get_bit_depth(png, info) != 8 || png_get_channels(png, info) != 4 || rowBytes != 4ull * width)
        png_error(png, "cannot convert the image to 8-bit RGBA");

    std::vector<std::uint8_t>& rgba = *out->pixels;
    if (passes > 1) {
        // Interlaced: every pass refines all rows, so the whole image is needed from the start.
        rgba.assign(rowBytes * height, 0);
        for (int pass = 0; pass < passes; ++pass)
            for (png_uint_32 y = 0; y < height; ++y) png_read_row(png, rgba.data() + rowBytes * y, nullptr);
    } else {
        rgba.clear();
        for (png_uint_32 y = 0; y < height; ++y) {
            rgba.resize(rowBytes * (y + 1));  // grows with the data actually present
            png_read_row(png, rgba.data() + rowBytes * y, nullptr);
        }
    }
    png_read_end(png, nullptr);  // a file cut off after its pixel data is still truncated
    out->width = width;
    out->height = height;
    return true;
}

/// All libpng calls of a write (same rules as decodePng).
bool encodePng(png_structp png, png_infop info, std::FILE* file, const Image* image) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, file);
    png_set_IHDR(png, info, static_cast<png_uint_32>(image->width), static_cast<png_uint_32>(image->height), 8,
                 PNG_COLOR_TYPE_RGB_ALPHA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    const std::size_t rowBytes = 4 * static_cast<std::size_t>(image->width);
    for (int y = 0; y < image->height; ++y)
        png_write_row(png, image->rgba.data() + rowBytes * static_cast<std::size_t>(y));
    png_write_end(png, nullptr);
    return true;
}

/// Reads the whole file (at most kMaxFileBytes).
std::vector<std::uint8_t> readFile(const std::string& path) {
    errno = 0;
    File file(std::fopen(path.c_str(), "rb"));
    if (!file) throw std::runtime_error(path + ": cannot open: " + systemError());
    std::vector<std::uint8_t> bytes;
    std::uint8_t buffer[1 << 16];
    for (;;) {
        const std::size_t n = std::fread(buffer, 1, sizeof buffer, file.get());
        bytes.insert(bytes.end(), buffer, buffer + n);
        if (bytes.size() > kMaxFileBytes) throw std::runtime_error(path + ": file larger than 1 GiB");
        if (n < sizeof buffer) break;
    }
    if (std::ferror(file.get())) throw std::runtime_error(path + ": cannot read: " + systemError());
    return bytes;
}

}  // namespace

void writePng(const std::string& path, const Image& image) {
    requireValid(image, "writePng(" + path + ")");
    PngError error;
    PngWriteStruct png(error);
    if (!png.ok()) throw std::runtime_error(path + ": cannot write PNG: libpng initialisation failed");
    errno = 0;
    File file(std::fopen(path.c_str(), "wb"));
    if (!file) throw std::runtime_error(path + ": cannot open for writing: " + systemError());
    std::string failure;
    if (!encodePng(png.png(), png.info(), file.get(), &image)) {
        failure = std::string("cannot write PNG: ") + error.message;
    } else if (std::fflush(file.get()) != 0 || std::ferror(file.get())) {
        failure = "cannot write: " + systemError();  // e.g. the disk is full (seen when the buffer is flushed)
    }
    if (failure.empty() && std::fclose(file.release()) != 0) failure = "cannot write: " + systemError();
    if (!failure.empty()) {
        file.reset();
        std::remove(path.c_str());  // no truncated PNG left behind
        throw std::runtime_error(path + ": " + failure);
    }
}

Image readPng(const std::string& path) {
    const std::vector<std::uint8_t> bytes = readFile(path);
    if (bytes.empty()) throw std::runtime_error(path + ": not a PNG file (empty)");
    if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0)
        throw std::runtime_error(path + ": not a PNG file (no PNG signature)");
    PngError error;
    PngReadStruct png(error);
    if (!png.ok()) throw std::runtime_error(path + ": cannot read PNG: libpng initialisation failed");
    MemoryInput input{bytes.data(), bytes.size(), 0};
    std::vector<std::uint8_t> pixels;
    Decoded decoded;
    decoded.pixels = &pixels;
    if (!decodePng(png.png(), png.info(), &input, &decoded))
        throw std::runtime_error(path + ": cannot read PNG: " + error.message);
    Image image;
    image.width = static_cast<int>(decoded.width);
    image.height = static_cast<int>(decoded.height);
    image.rgba = std::move(pixels);
    return image;
}

Image makeContactSheet(const std::vector<Image>& images, int columns, int border,
                       std::array<std::uint8_t, 3> borderColour) {
    if (images.empty()) throw std::invalid_argument("makeContactSheet: no images");
    if (columns < 1) throw std::invalid_argument("makeContactSheet: columns must be at least 1");
    if (border < 0 || border > kMaxBorder) throw std::invalid_argument("makeContactSheet: border must be 0..1024");
    int cellWidth = 0, cellHeight = 0;
    for (std::size_t i = 0; i < images.size(); ++i) {
        requireValid(images[i], "makeContactSheet: image " + std::to_string(i));
        cellWidth = std::max(cellWidth, images[i].width);
        cellHeight = std::max(cellHeight, images[i].height);
    }
    const std::int64_t cols = std::min<std::int64_t>(columns, static_cast<std::int64_t>(images.size()));
    const std::int64_t rows = (static_cast<std::int64_t>(images.size()) + cols - 1) / cols;
    const std::int64_t width = cols * cellWidth + (cols + 1) * border;
    const std::int64_t height = rows * cellHeight + (rows + 1) * border;
    if (width > kMaxSheetSize || height > kMaxSheetSize)
        throw std::invalid_argument("makeContactSheet: the sheet would be " + std::to_string(width) + "x" +
                                    std::to_string(height) + " pixels (at most 65535 in each direction)");
    Image sheet;
    sheet.width = static_cast<int>(width);
    sheet.height = static_cast<int>(height);
    const std::size_t sheetRow = 4 * static_cast<std::size_t>(sheet.width);
    sheet.rgba.resize(sheetRow * static_cast<std::size_t>(sheet.height));
    for (std::size_t p = 0; p < sheet.rgba.size(); p += 4) {
        sheet.rgba[p] = borderColour[0];
        sheet.rgba[p + 1] = borderColour[1];
        sheet.rgba[p + 2] = borderColour[2];
        sheet.rgba[p + 3] = 255;
    }
    for (std::size_t i = 0; i < images.size(); ++i) {
        const Image& image = images[i];
        const std::int64_t col = static_cast<std::int64_t>(i) % cols;
        const std::int64_t row = static_cast<std::int64_t>(i) / cols;
        const std::int64_t x0 = border + col * (cellWidth + border) + (cellWidth - image.width) / 2;
        const std::int64_t y0 = border + row * (cellHeight + border) + (cellHeight - image.height) / 2;
        const std::size_t imageRow = 4 * static_cast<std::size_t>(image.width);
        for (int y = 0; y < image.height; ++y) {
            std::memcpy(sheet.rgba.data() + static_cast<std::size_t>(y0 + y) * sheetRow + 4 * static_cast<std::size_t>(x0),
                        image.rgba.data() + static_cast<std::size_t>(y) * imageRow, imageRow);
        }
    }
    return sheet;
}

Image downscale(const Image& image, int factor) {
    requireValid(image, "downscale");
    if (factor < 1) throw std::invalid_argument("downscale: factor must be at least 1, got " + std::to_string(factor));
    Image out;
    out.width = image.width / factor + (image.width % factor != 0 ? 1 : 0);
    out.height = image.height / factor + (image.height % factor != 0 ? 1 : 0);
    out.rgba.resize(4 * static_cast<std::size_t>(out.width) * static_cast<std::size_t>(out.height));
    std::vector<std::uint64_t> sums(4 * static_cast<std::size_t>(out.width));
    for (int oy = 0; oy < out.height; ++oy) {
        std::fill(sums.begin(), sums.end(), 0);
        const int y0 = oy * factor;
        const int y1 = static_cast<int>(std::min<std::int64_t>(static_cast<std::int64_t>(y0) + factor, image.height));
        for (int y = y0; y < y1; ++y) {
            const std::uint8_t* src = image.rgba.data() + 4 * static_cast<std::size_t>(y) * image.width;
            for (int x = 0; x < image.width; ++x, src += 4) {
                std::uint64_t* sum = &sums[4 * static_cast<std::size_t>(x / factor)];
                for (int c = 0; c < 4; ++c) sum[c] += src[c];
            }
        }
        for (int ox = 0; ox < out.width; ++ox) {
            const std::int64_t x0 = static_cast<std::int64_t>(ox) * factor;
            const std::int64_t x1 = std::min<std::int64_t>(x0 + factor, image.width);
            const std::uint64_t count = static_cast<std::uint64_t>((x1 - x0) * (y1 - y0));
            std::uint8_t* dst = out.rgba.data() + 4 * (static_cast<std::size_t>(oy) * out.width + ox);
            for (int c = 0; c < 4; ++c)
                dst[c] = static_cast<std::uint8_t>((sums[4 * static_cast<std::size_t>(ox) + c] + count / 2) / count);
        }
    }
    return out;
}

}  // namespace cullide::io
