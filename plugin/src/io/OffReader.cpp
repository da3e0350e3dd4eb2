// The OFF reader and writer. The counts are trusted only as far as the input can back them (the reservations are
// bounded by the bytes left in the stream); a vertex count that does not match the file is told apart from a
// malformed record where the evidence allows (vertex lines that look like faces, a first face that looks like a
// vertex).
#include "io/TokenReader.h"

#include "cullide/io/MeshIO.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cstdint>
#include <istream>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace cullide::io {

namespace {

using detail::addFan;
using detail::isInteger;
using detail::kMaxVertices;
using detail::parseInt;
using detail::quote;
using detail::TokenReader;

/// Reservation cap when the stream size is unknown (non-seekable streams): vectors then grow with the input.
constexpr std::size_t kUnknownSizeReserve = 4096;

/// Bytes left in the stream, or SIZE_MAX when the stream cannot tell (not seekable).
std::size_t remainingBytes(std::istream& in) {
    const std::streampos pos = in.tellg();
    if (pos == std::streampos(-1)) {
        in.clear(in.rdstate() & ~std::ios::failbit);
        return std::numeric_limits<std::size_t>::max();
    }
    std::size_t result = std::numeric_limits<std::size_t>::max();
    if (in.seekg(0, std::ios::end)) {
        const std::streampos end = in.tellg();
        if (end != std::streampos(-1) && end >= pos) result = static_cast<std::size_t>(end - pos);
    }
    in.clear();
    in.seekg(pos);
    in.clear();
    return result;
}

/// How many items of a declared count may be reserved, given that each needs at least `minBytes` of input.
std::size_t boundedReserve(std::uint64_t declared, std::size_t remaining, std::size_t minBytes) {
    const std::size_t byInput = remaining == std::numeric_limits<std::size_t>::max()
                                    ? kUnknownSizeReserve
                                    : remaining / minBytes + 1;
    return static_cast<std::size_t>(std::min<std::uint64_t>(declared, byInput));
}

bool isOffHeader(std::string_view t) { return t == "OFF" || t == "COFF" || t == "NOFF" || t == "CNOFF"; }

bool endsWithOff(std::string_view t) {
    if (t.size() < 3) return false;
    std::string tail(t.substr(t.size() - 3));
    std::transform(tail.begin(), tail.end(), tail.begin(), [](char c) {
        return static_cast<char>(c >= 'a' && c <= 'z' ? c - 'a' + 'A' : c);
    });
    return tail == "OFF";
}

// ---------------------------------------------------------------------------------------------------------------
// OFF records

struct OffCounts {
    std::uint64_t vertices = 0;
    std::uint64_t faces = 0;
    std::size_t line = 0;  ///< where the counts are
};

/// "OFF" (or a variant), then "vertices faces [edges]" on the same or a later line.
OffCounts readOffCounts(TokenReader& r) {
    if (!r.nextRecord()) r.failAtEnd("empty file: expected the 'OFF' header or the vertex/face counts");
    bool header = false;
    if (isOffHeader(r.token())) {
        header = true;
        if (!r.next() && !r.nextRecord()) r.failAtEnd("unexpected end of file: expected the vertex/face counts");
    } else if (endsWithOff(r.token())) {
        r.fail("unsupported OFF variant " + quote(r.token()) + " (OFF, COFF, NOFF and CNOFF are read)");
    }
    std::array<std::int64_t, 3> counts{0, 0, 0};
    std::size_t n = 0;
    do {
        if (n == counts.size()) r.fail("too many values on the counts line (expected 'vertices faces [edges]')");
        std::int64_t v = 0;
        bool overflow = false;
        if (n == 0 && !header && !parseInt(r.token(), v, overflow) && !overflow) {
            r.fail("expected the 'OFF' header or the vertex/face counts, found " + quote(r.token()));
        }
        counts[n] = r.integer(r.token(), "count");
        if (counts[n] < 0) r.fail("negative count " + quote(r.token()));
        ++n;
    } while (r.next());
    if (n < 2) r.fail("missing counts: expected 'vertices faces [edges]'");
    OffCounts c;
    c.vertices = static_cast<std::uint64_t>(counts[0]);
    c.faces = static_cast<std::uint64_t>(counts[1]);
    c.line = r.line();
    if (c.vertices > kMaxVertices) {
        r.fail("vertex count " + std::to_string(c.vertices) + " is too large (at most " +
               std::to_string(kMaxVertices) + ")");
    }
    return c;
}

/// Vertex lines that look like faces ("n i1 ... in", all integers, perhaps a colour): evidence that the vertex
/// count is larger than the vertex lines of the file.
struct FaceLikeVertices {
    std::size_t count = 0;
    std::size_t firstLine = 0;
    std::uint64_t firstIndex = 0;  ///< vertex lines before the first one

    std::string explain(const OffCounts& c) const {
        return "line " + std::to_string(firstLine) + " looks like a face, not a vertex: the vertex count " +
               std::to_string(c.vertices) + " on line " + std::to_string(c.line) +
               " is probably too large (the file has " + std::to_string(firstIndex) + " vertex lines before it)";
    }
};

/// "x y z [colour...]"; `faceLike` says whether the record looks like a face instead.
Vec3 readOffVertex(TokenReader& r, bool& faceLike) {
    std::int64_t first = 0;
    bool allIntegers = isInteger(r.token(), first);
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
        if (k > 0 && !r.next()) r.fail("vertex needs 3 coordinates, found " + std::to_string(k));
        std::int64_t i = 0;
        allIntegers = allIntegers && isInteger(r.token(), i);
        p[k] = r.number("vertex coordinate");
    }
    const std::size_t extra = r.trailingNumbers("vertex coordinates", allIntegers);
    // A polygon "n i1 ... in" has n + 1 integers, n + 4 or n + 5 with an RGB(A) colour. Compared as tokens - n, and
    // only for n >= 3: both are then positive, so the difference cannot overflow where n + 4 could (n up to
    // 2^63 - 1), nor tokens - n for a negative n (down to -2^63 + 1).
    const bool countLike = allIntegers && first >= 3;
    const std::int64_t beyondCount = countLike ? static_cast<std::int64_t>(3 + extra) - first : 0;
    faceLike = countLike && (beyondCount == 1 || beyondCount == 4 || beyondCount == 5);
    return p;
}

/// "n i1 ... in [colour...]", fanned into `mesh`.
void readOffFace(TokenReader& r, std::uint64_t nv, std::vector<std::uint32_t>& polygon, TriangleMesh& mesh) {
    const std::int64_t n = r.integer(r.token(), "face vertex count");
    if (n < 3) r.fail("face has " + std::to_string(n) + " vertices (at least 3 are needed)");
    polygon.clear();
    for (std::int64_t k = 0; k < n; ++k) {
        if (!r.next()) r.fail("face declares " + std::to_string(n) + " vertices but lists " + std::to_string(k));
        const std::int64_t idx = r.integer(r.token(), "vertex index");
        if (idx < 0) r.fail("negative vertex index " + std::to_string(idx));
        if (static_cast<std::uint64_t>(idx) >= nv) {
            r.fail("vertex index " + std::to_string(idx) + " out of range (" + std::to_string(nv) + " vertices)");
        }
        polygon.push_back(static_cast<std::uint32_t>(idx));
    }
    bool allIntegers = true;
    r.trailingNumbers("face indices (only a colour may follow)", allIntegers);
    addFan(mesh, polygon);
}

}  // namespace

TriangleMesh readOff(std::istream& in, const std::string& name) {
    const std::size_t remaining = remainingBytes(in);
    TokenReader r(in, name);
    TriangleMesh mesh;

    const OffCounts c = readOffCounts(r);
    // "0 0 0\n" is the shortest vertex record, "3 0 0 0\n" the shortest face.
    mesh.vertices.reserve(boundedReserve(c.vertices, remaining, 6));
    mesh.triangles.reserve(boundedReserve(c.faces, remaining, 8));

    FaceLikeVertices faceLike;
    for (std::uint64_t i = 0; i < c.vertices; ++i) {
        if (!r.nextRecord()) {
            // The counts line is what is wrong when faces were read as vertices.
            if (faceLike.count > 0) {
                throw ParseError(name, c.line,
                                 "the file ends after " + std::to_string(i) + " of the " +
                                     std::to_string(c.vertices) + " declared vertices; " + faceLike.explain(c));
            }
            r.failAtEnd("unexpected end of file: expected " + std::to_string(c.vertices) + " vertices and " +
                        std::to_string(c.faces) + " faces (counts on line " + std::to_string(c.line) +
                        "), found " + std::to_string(i) + " vertices");
        }
        bool looksLikeFace = false;
        mesh.vertices.push_back(readOffVertex(r, looksLikeFace));
        if (looksLikeFace && faceLike.count++ == 0) {
            faceLike.firstLine = r.line();
            faceLike.firstIndex = i;
        }
    }

    std::vector<std::uint32_t> polygon;
    for (std::uint64_t f = 0; f < c.faces; ++f) {
        if (!r.nextRecord()) {
            r.failAtEnd("unexpected end of file: expected " + std::to_string(c.faces) + " faces (counts on line " +
                        std::to_string(c.line) + "), found " + std::to_string(f) +
                        (faceLike.count > 0 ? "; " + faceLike.explain(c) : std::string()));
        }
        // A first face that is not one is most likely a vertex the vertex count left out.
        r.setHint(f == 0 && c.vertices > 0 ? " (line " + std::to_string(r.line()) +
                                                  " should be the first face; if it is a vertex, the vertex count " +
                                                  std::to_string(c.vertices) + " on line " +
                                                  std::to_string(c.line) + " is too small)"
                                            : std::string());
        readOffFace(r, c.vertices, polygon, mesh);
    }
    r.setHint("");

    if (r.nextRecord()) {
        r.fail("unexpected data after the last of the " + std::to_string(c.faces) + " declared faces (counts on line " +
               std::to_string(c.line) + "): " + quote(r.token()));
    }
    return mesh;
}

void writeOff(const TriangleMesh& mesh, std::ostream& out) {
    std::string buf;
    buf.reserve(1 << 16);
    auto flush = [&] {
        out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
        buf.clear();
    };
    buf += "OFF\n";
    buf += std::to_string(mesh.vertices.size());
    buf += ' ';
    buf += std::to_string(mesh.triangles.size());
    buf += " 0\n";
    char num[64];
    for (const Vec3& p : mesh.vertices) {
        for (int k = 0; k < 3; ++k) {
            // Shortest representation that reads back to the same double.
            auto res = std::to_chars(num, num + sizeof(num), p[k]);
            buf.append(num, res.ptr);
            buf += k < 2 ? ' ' : '\n';
        }
        if (buf.size() > (1 << 16) - 256) flush();
    }
    for (const TriangleIndices& t : mesh.triangles) {
        buf += "3";
        for (const std::uint32_t i : t) {
            buf += ' ';
            auto res = std::to_chars(num, num + sizeof(num), i);
            buf.append(num, res.ptr);
        }
        buf += '\n';
        if (buf.size() > (1 << 16) - 256) flush();
    }
    flush();
}

}  // namespace cullide::io
