// OFF / OBJ readers, the OFF writer and the cullide-pairs scene reader.
//
// All readers are strict: every malformed input ends in ParseError(file, line, message), never in a crash, a hang or
// a huge allocation. The mesh readers take their tokens straight from the stream, one at a time and only as many as
// the record being parsed needs, so their time is linear in the bytes they read and their memory is the mesh they
// build plus one token: a hostile 50 MB line is rejected after its first bad token. Declared counts are only trusted
// as far as the input can back them: the reservations are bounded by the number of bytes left in the stream.
// Messages are bounded too: names and tokens are shown escaped and shortened.
#include "cullide/io/MeshIO.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <map>
#include <ostream>
#include <sstream>
#include <streambuf>
#include <string_view>
#include <system_error>

namespace cullide::io {

namespace {

/// Longest name (file path) and message shown in an error, in bytes; longer ones are cut.
constexpr std::size_t kMaxShownName = 200;
constexpr std::size_t kMaxShownMessage = 1000;

/// `s` for an error message: control bytes escaped (\0, \n, \t, \xNN), cut after `max` bytes (not inside a UTF-8
/// sequence) with the full size noted.
std::string printable(std::string_view s, std::size_t max) {
    std::size_t n = std::min(s.size(), max);
    if (n < s.size()) {
        while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;  // not inside a UTF-8 sequence
    }
    std::string out;
    out.reserve(n + 32);
    for (std::size_t i = 0; i < n; ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c == 0) {
            out += "\\0";
        } else if (c == '\n') {
            out += "\\n";
        } else if (c == '\t') {
            out += "\\t";
        } else if (c < 0x20 || c == 0x7f) {
            static const char* hex = "0123456789abcdef";
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        } else {
            out += static_cast<char>(c);
        }
    }
    if (n < s.size()) out += "... (" + std::to_string(s.size()) + " bytes)";
    return out;
}

std::string formatParseError(const std::string& file, std::size_t line, const std::string& message) {
    std::string s = printable(file, kMaxShownName);
    if (line > 0) {
        s += ':';
        s += std::to_string(line);
    }
    s += ": ";
    s += printable(message, kMaxShownMessage);
    return s;
}

}  // namespace

ParseError::ParseError(const std::string& file, std::size_t line, const std::string& message)
    : std::runtime_error(formatParseError(file, line, message)), m_file(file), m_line(line) {}

namespace {

constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();
/// Reservation cap when the stream size is unknown (non-seekable streams): vectors then grow with the input.
constexpr std::size_t kUnknownSizeReserve = 4096;
/// Longest mesh path a scene may name (PATH_MAX on Linux).
constexpr std::size_t kMaxPathBytes = 4096;

// ---------------------------------------------------------------------------------------------------------------
// Tokens and numbers

bool isSpace(int c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Printable text, tabs and line-break characters, and bytes >= 0x80 (UTF-8 in comments and names) are text;
/// any other control byte means the input is not a text file.
bool isBinaryByte(unsigned char c) {
    return (c < 0x20 && c != '\t' && c != '\r' && c != '\v' && c != '\f' && c != '\n') || c == 0x7f;
}

/// Shortens a token for an error message (binary garbage can make tokens arbitrarily long and unprintable).
std::string quote(std::string_view token) {
    std::string s = "'";
    const std::size_t n = std::min<std::size_t>(token.size(), 32);
    for (std::size_t i = 0; i < n; ++i) {
        const auto c = static_cast<unsigned char>(token[i]);
        if (c >= 0x20 && c < 0x7f) {
            s += static_cast<char>(c);
        } else {
            static const char* hex = "0123456789abcdef";
            s += "\\x";
            s += hex[c >> 4];
            s += hex[c & 15];
        }
    }
    if (token.size() > n) s += "...";
    s += "'";
    return s;
}

/// Parses a whole token as a decimal floating-point number (an optional '+' is accepted). Out-of-range values
/// that underflow become zero or subnormal; overflow makes the value infinite, which callers reject.
bool parseDouble(std::string_view s, double& out) {
    if (!s.empty() && s.front() == '+') {
        s.remove_prefix(1);
        if (s.empty() || s.front() == '+' || s.front() == '-') return false;
    }
    if (s.empty()) return false;
    const char* end = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(s.data(), end, out);
    if (ptr != end) return false;
    if (ec == std::errc::result_out_of_range) {
        // Tell underflow (a tiny but valid number) from overflow: redo it in the wider type.
        long double wide = 0.0L;
        auto [wptr, wec] = std::from_chars(s.data(), end, wide);
        if (wptr != end || wec != std::errc()) {
            out = std::numeric_limits<double>::infinity();
            return true;
        }
        out = static_cast<double>(wide);
        return true;
    }
    return ec == std::errc();
}

/// Parses a whole token as a decimal integer (an optional '+' is accepted).
bool parseInt(std::string_view s, std::int64_t& out, bool& overflow) {
    overflow = false;
    if (!s.empty() && s.front() == '+') {
        s.remove_prefix(1);
        if (s.empty() || s.front() == '+' || s.front() == '-') return false;
    }
    if (s.empty()) return false;
    const char* end = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(s.data(), end, out);
    if (ptr != end) return false;
    if (ec == std::errc::result_out_of_range) {
        overflow = true;
        return false;
    }
    return ec == std::errc();
}

bool isInteger(std::string_view s, std::int64_t& out) {
    bool overflow = false;
    return parseInt(s, out, overflow);
}

// ---------------------------------------------------------------------------------------------------------------
// Token reading

/// Reads whitespace-separated tokens straight from the stream buffer, a record (one line) at a time and only as
/// far as the parser asks: nothing is proportional to a line's length. '#' starts a comment that runs to the end of
/// the line. Every byte consumed is checked for binary data; a UTF-8 byte-order mark at the start is skipped.
class TokenReader {
public:
    TokenReader(std::istream& in, const std::string& name) : m_buf(in.rdbuf()), m_name(name) {
        if (m_buf == nullptr) throw ParseError(name, 0, "read error (the stream has no buffer)");
    }

    /// Leaves the current record (the rest of its line is skipped) and reads the first token of the next line that
    /// has one; false at the end of input.
    bool nextRecord() {
        if (m_inRecord) skipLine();
        m_inRecord = false;
        while (true) {
            if (readToken()) {
                m_inRecord = true;
                return true;
            }
            if (m_buf->sbumpc() == kEof) return false;  // else it was the '\n'
            newLine();
        }
    }
    /// The next token of the current record; false at the end of its line.
    bool next() { return m_inRecord && readToken(); }
    /// The current token; valid until the next call to next() or nextRecord().
    std::string_view token() const { return m_token; }
    /// 1-based line of the current record.
    std::size_t line() const { return m_line; }

    /// Appended to every message (context such as "the vertex count may be too small"); empty for none.
    void setHint(std::string hint) { m_hint = std::move(hint); }
    [[noreturn]] void fail(const std::string& message) const { throw ParseError(m_name, m_line, message + m_hint); }
    /// For errors at the end of input: the line where the missing record was expected.
    [[noreturn]] void failAtEnd(const std::string& message) const {
        throw ParseError(m_name, m_atLineStart ? m_line : m_line + 1, message + m_hint);
    }

    double number(const char* what) const {
        double v = 0.0;
        if (!parseDouble(m_token, v)) fail(std::string("invalid ") + what + " " + quote(m_token));
        if (!std::isfinite(v)) fail(std::string(what) + " " + quote(m_token) + " is not a finite number");
        return v;
    }
    std::int64_t integer(std::string_view token, const char* what) const {
        std::int64_t v = 0;
        bool overflow = false;
        if (!parseInt(token, v, overflow)) {
            if (overflow) fail(std::string(what) + " " + quote(token) + " is out of range");
            fail(std::string("invalid ") + what + " " + quote(token) + " (an integer is expected)");
        }
        return v;
    }
    /// The rest of the record must be numbers (optional colour values, normals, w). Returns how many there were;
    /// `allIntegers` is cleared when one is not an integer.
    std::size_t trailingNumbers(const char* after, bool& allIntegers) {
        std::size_t n = 0;
        while (next()) {
            double v = 0.0;
            if (!parseDouble(m_token, v)) fail(std::string("unexpected token ") + quote(m_token) + " after the " + after);
            std::int64_t i = 0;
            allIntegers = allIntegers && isInteger(m_token, i);
            ++n;
        }
        return n;
    }

private:
    static constexpr int kEof = std::char_traits<char>::eof();

    /// Consumes one byte of a token, a space or a comment (never the '\n'); rejects binary data.
    void consume(int c) {
        m_buf->sbumpc();
        m_atLineStart = false;
        ++m_offset;
        if (isBinaryByte(static_cast<unsigned char>(c))) {
            const char byte = static_cast<char>(c);
            fail("binary data (control byte " + quote(std::string_view(&byte, 1)) + "): not a text file");
        }
    }
    void newLine() {
        ++m_line;
        ++m_offset;
        m_atLineStart = true;
    }
    /// Skips spaces and a comment, then reads a token into m_token; false at the end of the line or of the input
    /// (the '\n' is left unread).
    bool readToken() {
        while (true) {
            int c = m_buf->sgetc();
            while (isSpace(c)) {
                consume(c);
                c = m_buf->sgetc();
            }
            if (c == '#') {
                while (c != '\n' && c != kEof) {
                    consume(c);
                    c = m_buf->sgetc();
                }
            }
            if (c == '\n' || c == kEof) return false;
            const bool atStart = m_offset == 0;
            m_token.clear();
            while (c != '\n' && c != kEof && c != '#' && !isSpace(c)) {
                consume(c);
                if (m_token.size() == kMaxMeshTokenBytes) {
                    fail("token longer than " + std::to_string(kMaxMeshTokenBytes) + " bytes: " + quote(m_token));
                }
                m_token += static_cast<char>(c);
                c = m_buf->sgetc();
            }
            if (atStart && m_token.compare(0, 3, "\xEF\xBB\xBF") == 0) m_token.erase(0, 3);  // byte-order mark
            if (!m_token.empty()) return true;
        }
    }
    /// Skips the rest of the current line, its '\n' included.
    void skipLine() {
        int c = m_buf->sgetc();
        while (c != '\n' && c != kEof) {
            consume(c);
            c = m_buf->sgetc();
        }
        if (c == '\n') {
            m_buf->sbumpc();
            newLine();
        }
    }

    std::streambuf* m_buf;
    const std::string& m_name;
    std::string m_token;
    std::string m_hint;
    std::size_t m_line = 1;
    std::size_t m_offset = 0;
    bool m_atLineStart = true;
    bool m_inRecord = false;
};

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

void addFan(TriangleMesh& mesh, const std::vector<std::uint32_t>& polygon) {
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
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
    // A polygon "n i1 ... in" has n + 1 integers, n + 4 or n + 5 with an RGB(A) colour. Compared as tokens - n: both
    // are positive, so the difference cannot overflow where n + 4 could (n up to 2^63 - 1).
    const std::int64_t beyondCount = static_cast<std::int64_t>(3 + extra) - first;
    faceLike = allIntegers && first >= 3 && (beyondCount == 1 || beyondCount == 4 || beyondCount == 5);
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

// -------------------------------------------------------------------------------------------------------------------
// OFF

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

// -------------------------------------------------------------------------------------------------------------------
// OBJ

namespace {

bool isKeyword(std::string_view t) {
    auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
    if (t.empty() || !alpha(t[0])) return false;
    return std::all_of(t.begin(), t.end(), [&](char c) { return alpha(c) || (c >= '0' && c <= '9'); });
}

/// Faces that name a vertex defined further down (legal in OBJ): checked once all vertices are known.
struct PendingFace {
    std::size_t line;
    std::uint64_t maxIndex;
};

/// "v x y z [w | colour]".
Vec3 readObjVertex(TokenReader& r) {
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
        if (!r.next()) r.fail("vertex needs 3 coordinates, found " + std::to_string(k));
        p[k] = r.number("vertex coordinate");
    }
    bool allIntegers = true;
    r.trailingNumbers("vertex coordinates", allIntegers);
    return p;
}

/// One face vertex (v, v/vt, v//vn, v/vt/vn) as a 0-based index; `count` vertices are known so far.
std::int64_t readObjFaceVertex(const TokenReader& r, std::int64_t count) {
    const std::string_view ref = r.token();
    std::array<std::string_view, 3> parts{};
    std::size_t nParts = 0;
    std::size_t start = 0;
    while (true) {
        const std::size_t slash = ref.find('/', start);
        if (nParts == 3) r.fail("invalid face vertex " + quote(ref) + " (too many '/')");
        parts[nParts++] = ref.substr(start, slash == std::string_view::npos ? ref.npos : slash - start);
        if (slash == std::string_view::npos) break;
        start = slash + 1;
    }
    if (parts[0].empty()) r.fail("invalid face vertex " + quote(ref) + " (missing vertex index)");
    for (std::size_t p = 1; p < nParts; ++p) {
        if (parts[p].empty()) continue;
        if (r.integer(parts[p], "texture/normal index") == 0) {
            r.fail("invalid face vertex " + quote(ref) + " (index 0)");
        }
    }
    const std::int64_t v = r.integer(parts[0], "vertex index");
    if (v == 0) r.fail("vertex index 0 is invalid (OBJ indices start at 1)");
    if (v < 0) {
        if (count + v < 0) {
            r.fail("relative vertex index " + std::to_string(v) + " out of range (" + std::to_string(count) +
                   " vertices so far)");
        }
        return count + v;
    }
    if (static_cast<std::uint64_t>(v - 1) >= kMaxVertices) r.fail("vertex index " + std::to_string(v) + " out of range");
    return v - 1;
}

/// "f v1 v2 v3 ...", fanned into `mesh`; a face naming vertices not read yet goes to `pending`.
void readObjFace(TokenReader& r, std::vector<std::uint32_t>& polygon, TriangleMesh& mesh,
                 std::vector<PendingFace>& pending) {
    polygon.clear();
    std::uint64_t maxForward = 0;
    bool forward = false;
    const auto count = static_cast<std::int64_t>(mesh.vertices.size());
    while (r.next()) {
        const std::int64_t idx = readObjFaceVertex(r, count);
        if (idx >= count) {
            forward = true;
            maxForward = std::max(maxForward, static_cast<std::uint64_t>(idx));
        }
        polygon.push_back(static_cast<std::uint32_t>(idx));
    }
    if (polygon.size() < 3) {
        r.fail("face has " + std::to_string(polygon.size()) + " vertices (at least 3 are needed)");
    }
    if (forward) pending.push_back({r.line(), maxForward});
    addFan(mesh, polygon);
}

}  // namespace

TriangleMesh readObj(std::istream& in, const std::string& name) {
    TokenReader r(in, name);
    TriangleMesh mesh;
    std::vector<std::uint32_t> polygon;
    std::vector<PendingFace> pending;

    while (r.nextRecord()) {
        const std::string_view kw = r.token();
        if (kw == "v") {
            if (mesh.vertices.size() >= kMaxVertices) r.fail("too many vertices");
            mesh.vertices.push_back(readObjVertex(r));
        } else if (kw == "f") {
            readObjFace(r, polygon, mesh, pending);
        } else if (!isKeyword(kw)) {
            r.fail("unknown record " + quote(kw));
        }
        // Other records (vt, vn, g, o, s, usemtl, mtllib, l, ...) are ignored: nextRecord() skips their line.
    }

    for (const PendingFace& p : pending) {
        if (p.maxIndex >= mesh.vertices.size()) {
            throw ParseError(name, p.line,
                             "vertex index " + std::to_string(p.maxIndex + 1) + " out of range (" +
                                 std::to_string(mesh.vertices.size()) + " vertices)");
        }
    }
    return mesh;
}

// -------------------------------------------------------------------------------------------------------------------
// Files

namespace {

std::string lowerExtension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](char c) {
        return static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
    });
    return ext;
}

/// Why `path` cannot be read as a regular file, or "" when it can. Says what is actually wrong: missing, a dangling
/// link, a path the system cannot resolve (a symbolic-link loop, a name too long: the system's reason), a directory.
std::string fileProblem(const std::string& path) {
    if (path.empty()) return "empty path";
    if (path.find('\0') != std::string::npos) return "the path contains a NUL byte (\\0)";
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (status.type() == std::filesystem::file_type::not_found) {
        std::error_code linkEc;
        if (std::filesystem::is_symlink(std::filesystem::symlink_status(path, linkEc))) {
            return "dangling symbolic link (its target does not exist)";
        }
        return "file does not exist";
    }
    if (ec) return "cannot resolve the path: " + ec.message();
    if (std::filesystem::is_directory(status)) return "a directory, not a file";
    if (!std::filesystem::is_regular_file(status)) return "not a regular file";
    return "";
}

std::string checkedExtension(const std::string& path, std::string& problem) {
    const std::string ext = lowerExtension(path);
    problem.clear();
    if (ext != ".off" && ext != ".obj") {
        problem = "unsupported mesh format '" + printable(ext, 32) + "' (.off and .obj are read)";
    }
    return ext;
}

void openForReading(const std::string& path, std::ifstream& in) {
    if (const std::string problem = fileProblem(path); !problem.empty()) throw ParseError(path, 0, problem);
    in.open(path, std::ios::binary);
    if (!in) throw ParseError(path, 0, "cannot open the file for reading");
}

}  // namespace

TriangleMesh readMesh(const std::string& path) {
    // The file first: a missing file is reported as missing whatever its name.
    if (const std::string problem = fileProblem(path); !problem.empty()) throw ParseError(path, 0, problem);
    std::string problem;
    const std::string ext = checkedExtension(path, problem);
    if (!problem.empty()) throw ParseError(path, 0, problem);
    std::ifstream in;
    openForReading(path, in);
    return ext == ".off" ? readOff(in, path) : readObj(in, path);
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

// -------------------------------------------------------------------------------------------------------------------
// Scene files

namespace {

/// Finds where values sit in a JSON text that nlohmann has already accepted, to give semantic errors a line.
class JsonLocator {
public:
    static constexpr std::size_t npos = std::string::npos;

    explicit JsonLocator(const std::string& text) : m_text(text) {
        for (std::size_t i = 0; i < text.size(); ++i) {
            if (text[i] == '\n') m_newlines.push_back(i);
        }
        if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) m_start = 3;
    }

    /// 1-based line of byte offset `pos` (npos: line 1).
    std::size_t lineOf(std::size_t pos) const {
        if (pos == npos) return 1;
        return static_cast<std::size_t>(std::lower_bound(m_newlines.begin(), m_newlines.end(), pos) -
                                        m_newlines.begin()) +
               1;
    }
    std::size_t root() const { return skipWs(m_start); }

    /// Offset of the value of member `key` in the object at `pos` (the last one when repeated), or npos.
    std::size_t member(std::size_t pos, std::string_view key) const {
        if (pos >= m_text.size() || m_text[pos] != '{') return npos;
        std::size_t found = npos;
        std::size_t i = skipWs(pos + 1);
        while (i < m_text.size() && m_text[i] == '"') {
            const std::size_t keyEnd = skipString(i);
            const bool match = keyEquals(i, keyEnd, key);
            i = skipWs(keyEnd);
            if (i >= m_text.size() || m_text[i] != ':') return found;
            i = skipWs(i + 1);
            if (match) found = i;
            i = skipWs(skipValue(i));
            if (i < m_text.size() && m_text[i] == ',') {
                i = skipWs(i + 1);
            } else {
                break;
            }
        }
        return found;
    }

    /// Offset of element `index` of the array at `pos`, or npos.
    std::size_t element(std::size_t pos, std::size_t index) const {
        if (pos >= m_text.size() || m_text[pos] != '[') return npos;
        std::size_t i = skipWs(pos + 1);
        for (std::size_t k = 0; i < m_text.size() && m_text[i] != ']'; ++k) {
            if (k == index) return i;
            i = skipWs(skipValue(i));
            if (i < m_text.size() && m_text[i] == ',') {
                i = skipWs(i + 1);
            } else {
                break;
            }
        }
        return npos;
    }

    /// Offset of the first number token that does not fit a double (nlohmann reports no position for those).
    std::size_t firstOverflowingNumber() const {
        std::size_t i = m_start;
        while (i < m_text.size()) {
            const char c = m_text[i];
            if (c == '"') {
                i = skipString(i);
            } else if (c == '-' || (c >= '0' && c <= '9')) {
                const std::size_t end = scalarEnd(i);
                double v = 0.0;
                if (parseDouble(std::string_view(m_text).substr(i, end - i), v) && !std::isfinite(v)) return i;
                i = end;
            } else {
                ++i;
            }
        }
        return npos;
    }

private:
    std::size_t skipWs(std::size_t i) const {
        while (i < m_text.size() &&
               (m_text[i] == ' ' || m_text[i] == '\t' || m_text[i] == '\n' || m_text[i] == '\r')) {
            ++i;
        }
        return i;
    }
    /// `i` at the opening quote; returns the offset after the closing quote.
    std::size_t skipString(std::size_t i) const {
        ++i;
        while (i < m_text.size() && m_text[i] != '"') i += m_text[i] == '\\' ? 2 : 1;
        return std::min(i + 1, m_text.size());
    }
    std::size_t scalarEnd(std::size_t i) const {
        while (i < m_text.size() && m_text[i] != ',' && m_text[i] != ']' && m_text[i] != '}' &&
               m_text[i] != ' ' && m_text[i] != '\t' && m_text[i] != '\n' && m_text[i] != '\r') {
            ++i;
        }
        return i;
    }
    /// Iterative (nesting depth is unbounded in the input).
    std::size_t skipValue(std::size_t i) const {
        if (i >= m_text.size()) return i;
        if (m_text[i] == '"') return skipString(i);
        if (m_text[i] != '{' && m_text[i] != '[') return scalarEnd(i);
        std::size_t depth = 0;
        while (i < m_text.size()) {
            const char c = m_text[i];
            if (c == '"') {
                i = skipString(i);
                continue;
            }
            if (c == '{' || c == '[') ++depth;
            if (c == '}' || c == ']') {
                if (--depth == 0) return i + 1;
            }
            ++i;
        }
        return i;
    }
    bool keyEquals(std::size_t begin, std::size_t end, std::string_view key) const {
        const std::string_view raw = std::string_view(m_text).substr(begin + 1, end - begin - 2);
        if (raw.find('\\') == std::string_view::npos) return raw == key;
        try {
            return nlohmann::json::parse(m_text.substr(begin, end - begin)).get<std::string>() == key;
        } catch (const nlohmann::json::exception&) {
            return false;
        }
    }

    const std::string& m_text;
    std::vector<std::size_t> m_newlines;
    std::size_t m_start = 0;
};

std::string stripJsonPrefix(const std::string& what) {
    // "[json.exception.parse_error.101] parse error at line 1, column 2: ..." -> "parse error at ...".
    if (!what.empty() && what[0] == '[') {
        const std::size_t close = what.find("] ");
        if (close != std::string::npos) return what.substr(close + 2);
    }
    return what;
}

std::string jsonTypeName(const nlohmann::json& j) { return j.type_name(); }

}  // namespace

namespace {

/// The whole scene text, at most kMaxSceneFileBytes.
std::string readSceneText(std::istream& in, const std::string& name) {
    std::string text;
    std::array<char, 1 << 16> chunk{};
    while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
        text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
        if (text.size() > kMaxSceneFileBytes) {
            throw ParseError(name, 0, "the scene is larger than " + std::to_string(kMaxSceneFileBytes >> 20) +
                                          " MiB (a scene lists mesh files and transforms, not geometry)");
        }
    }
    if (in.bad()) throw ParseError(name, 0, "read error");
    return text;
}

}  // namespace

std::vector<SceneObject> readSceneFile(const std::string& path) {
    std::ifstream in;
    openForReading(path, in);
    return readScene(in, path, std::filesystem::path(path).parent_path());
}

// `path` names the scene in errors (the file's path for readSceneFile).
std::vector<SceneObject> readScene(std::istream& in, const std::string& path, const std::filesystem::path& baseDir) {
    const std::string text = readSceneText(in, path);

    const JsonLocator loc(text);
    nlohmann::json doc;
    try {
        doc = nlohmann::json::parse(text, nullptr, true, false);
    } catch (const nlohmann::json::parse_error& e) {
        const std::size_t line = e.byte > 0 ? loc.lineOf(static_cast<std::size_t>(e.byte - 1)) : 1;
        throw ParseError(path, line, "invalid JSON: " + stripJsonPrefix(e.what()));
    } catch (const nlohmann::json::exception& e) {
        const std::size_t at = loc.firstOverflowingNumber();
        throw ParseError(path, loc.lineOf(at), "invalid JSON: " + stripJsonPrefix(e.what()));
    }

    const std::size_t rootPos = loc.root();
    if (!doc.is_object()) {
        throw ParseError(path, loc.lineOf(rootPos),
                         "the scene must be a JSON object with an \"objects\" array, found " + jsonTypeName(doc));
    }
    const auto objectsIt = doc.find("objects");
    if (objectsIt == doc.end()) throw ParseError(path, loc.lineOf(rootPos), "missing the \"objects\" array");
    const std::size_t objectsPos = loc.member(rootPos, "objects");
    if (!objectsIt->is_array()) {
        throw ParseError(path, loc.lineOf(objectsPos),
                         "\"objects\" must be an array, found " + jsonTypeName(*objectsIt));
    }

    std::map<std::string, std::shared_ptr<const TriangleMesh>> cache;  // a mesh used by several objects: read once
    std::vector<SceneObject> scene;
    scene.reserve(objectsIt->size());
    for (std::size_t i = 0; i < objectsIt->size(); ++i) {
        const nlohmann::json& obj = (*objectsIt)[i];
        const std::size_t objPos = loc.element(objectsPos, i);
        const std::string where = "objects[" + std::to_string(i) + "]";
        if (!obj.is_object()) {
            throw ParseError(path, loc.lineOf(objPos), where + " must be an object, found " + jsonTypeName(obj));
        }
        SceneObject so;

        const auto meshIt = obj.find("mesh");
        if (meshIt == obj.end()) throw ParseError(path, loc.lineOf(objPos), where + " has no \"mesh\"");
        const std::size_t meshPos = loc.member(objPos, "mesh");
        if (!meshIt->is_string()) {
            throw ParseError(path, loc.lineOf(meshPos),
                             where + ".mesh must be a string, found " + jsonTypeName(*meshIt));
        }
        so.meshPath = meshIt->get<std::string>();
        if (so.meshPath.empty()) throw ParseError(path, loc.lineOf(meshPos), where + ".mesh is empty");
        if (so.meshPath.size() > kMaxPathBytes) {
            throw ParseError(path, loc.lineOf(meshPos),
                             where + ".mesh is " + std::to_string(so.meshPath.size()) + " bytes long (paths have at most " +
                                 std::to_string(kMaxPathBytes) + "): \"" + printable(so.meshPath, kMaxShownName) + "\"");
        }
        if (so.meshPath.find('\0') != std::string::npos) {
            throw ParseError(path, loc.lineOf(meshPos),
                             where + ".mesh contains a NUL byte (\\0): \"" + printable(so.meshPath, kMaxShownName) +
                                 "\"");
        }

        const auto trIt = obj.find("transform");
        const std::size_t trPos = trIt == obj.end() ? objPos : loc.member(objPos, "transform");
        if (trIt != obj.end()) {
            if (!trIt->is_array() || trIt->size() != 16) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform must be an array of 16 numbers (row-major 4x4)");
            }
            for (std::size_t k = 0; k < 16; ++k) {
                const nlohmann::json& v = (*trIt)[k];
                const std::size_t vPos = loc.element(trPos, k);
                if (!v.is_number()) {
                    throw ParseError(path, loc.lineOf(vPos),
                                     where + ".transform[" + std::to_string(k) + "] must be a number, found " +
                                         jsonTypeName(v));
                }
                const double d = v.get<double>();
                if (!std::isfinite(d)) {
                    throw ParseError(path, loc.lineOf(vPos),
                                     where + ".transform[" + std::to_string(k) + "] is not finite");
                }
                so.transform(static_cast<Eigen::Index>(k / 4), static_cast<Eigen::Index>(k % 4)) = d;
            }
            if (so.transform.row(3) != Eigen::RowVector4d(0, 0, 0, 1)) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform is not affine (its last row must be 0 0 0 1)");
            }
        }

        std::filesystem::path meshFile(so.meshPath);
        if (meshFile.is_relative()) meshFile = baseDir / meshFile;
        const std::string meshFileName = meshFile.string();
        auto cached = cache.find(meshFileName);
        if (cached == cache.end()) {
            // Problems with the reference itself are reported at the scene's line (names shown shortened).
            std::string problem = fileProblem(meshFileName);
            if (problem.empty()) checkedExtension(meshFileName, problem);
            if (!problem.empty()) {
                throw ParseError(path, loc.lineOf(meshPos),
                                 where + ".mesh: " + problem + ": " + printable(meshFileName, kMaxShownName));
            }
            // Errors inside the mesh name the mesh file and its line.
            cached = cache.emplace(meshFileName, std::make_shared<const TriangleMesh>(readMesh(meshFileName))).first;
        }
        so.mesh = cached->second;
        so.toWorld.linear = so.transform.topLeftCorner<3, 3>();
        so.toWorld.translation = so.transform.topRightCorner<3, 1>();

        // Every vertex must land on a finite point (checked, not stored: the culler maps them itself).
        for (std::size_t v = 0; v < so.mesh->vertices.size(); ++v) {
            if (!transformPoint(so.toWorld, so.mesh->vertices[v]).allFinite()) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform maps vertex " + std::to_string(v) + " of " + so.meshPath +
                                     " to a non-finite point");
            }
        }
        scene.push_back(std::move(so));
    }
    return scene;
}

TriangleMesh worldMesh(const SceneObject& object) {
    TriangleMesh world;
    if (object.mesh == nullptr) return world;
    world.triangles = object.mesh->triangles;
    world.vertices.reserve(object.mesh->vertices.size());
    for (const Vec3& p : object.mesh->vertices) world.vertices.push_back(transformPoint(object.toWorld, p));
    return world;
}

}  // namespace cullide::io
