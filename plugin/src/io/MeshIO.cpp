// OFF / OBJ readers, the OFF writer and the cullide-pairs scene reader.
//
// All readers are line based and strict: every malformed input ends in ParseError(file, line, message), never in a
// crash, a hang or a huge allocation. Declared counts are only trusted as far as the input can back them: the
// reservations are bounded by the number of bytes left in the stream.
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
#include <string_view>
#include <system_error>

namespace cullide::io {

namespace {

std::string formatParseError(const std::string& file, std::size_t line, const std::string& message) {
    std::string s = file;
    if (line > 0) {
        s += ':';
        s += std::to_string(line);
    }
    s += ": ";
    s += message;
    return s;
}

}  // namespace

ParseError::ParseError(const std::string& file, std::size_t line, const std::string& message)
    : std::runtime_error(formatParseError(file, line, message)), m_file(file), m_line(line) {}

namespace {

constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();
/// Reservation cap when the stream size is unknown (non-seekable streams): vectors then grow with the input.
constexpr std::size_t kUnknownSizeReserve = 4096;

// ---------------------------------------------------------------------------------------------------------------
// Tokens and numbers

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Printable text, tabs and line-break characters, and bytes >= 0x80 (UTF-8 in comments and names) are text;
/// any other control byte means the input is not a text file.
bool isBinaryByte(unsigned char c) {
    return (c < 0x20 && c != '\t' && c != '\r' && c != '\v' && c != '\f' && c != '\n') || c == 0x7f;
}

/// Splits `line` into whitespace-separated tokens, ignoring everything from '#' on.
void tokenize(std::string_view line, std::vector<std::string_view>& tokens) {
    tokens.clear();
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(line[i])) ++i;
        const std::size_t start = i;
        while (i < line.size() && !isSpace(line[i])) ++i;
        if (i > start) tokens.push_back(line.substr(start, i - start));
    }
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

// ---------------------------------------------------------------------------------------------------------------
// Line reading

class LineReader {
public:
    LineReader(std::istream& in, const std::string& name) : m_in(in), m_name(name) {}

    /// Next line with at least one token (comments and blank lines skipped); false at end of input.
    bool nextContent() {
        while (nextLine()) {
            tokenize(m_line, m_tokens);
            if (!m_tokens.empty()) return true;
        }
        return false;
    }
    /// Next raw line (binary bytes rejected); false at end of input.
    bool nextLine() {
        if (!std::getline(m_in, m_line)) {
            if (m_in.bad()) throw ParseError(m_name, m_lineNo + 1, "read error");
            return false;
        }
        ++m_lineNo;
        if (m_lineNo == 1 && m_line.size() >= 3 && m_line.compare(0, 3, "\xEF\xBB\xBF") == 0) m_line.erase(0, 3);
        for (const char c : m_line) {
            if (isBinaryByte(static_cast<unsigned char>(c))) {
                throw ParseError(m_name, m_lineNo, "binary data (control byte " +
                                                       quote(std::string_view(&c, 1)) + "): not a text file");
            }
        }
        return true;
    }

    const std::vector<std::string_view>& tokens() const { return m_tokens; }
    std::size_t line() const { return m_lineNo; }
    [[noreturn]] void fail(const std::string& message) const { throw ParseError(m_name, m_lineNo, message); }
    /// For errors at the end of input: the line where the missing record was expected.
    [[noreturn]] void failAtEnd(const std::string& message) const {
        throw ParseError(m_name, m_lineNo + 1, message);
    }

    double number(std::string_view token, const char* what) const {
        double v = 0.0;
        if (!parseDouble(token, v)) fail(std::string("invalid ") + what + " " + quote(token));
        if (!std::isfinite(v)) fail(std::string(what) + " " + quote(token) + " is not a finite number");
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
    /// Tokens [from, end) must be numbers (optional colour values, normals, w).
    void checkTrailingNumbers(std::size_t from, const char* what) const {
        for (std::size_t i = from; i < m_tokens.size(); ++i) {
            double v = 0.0;
            if (!parseDouble(m_tokens[i], v)) {
                fail(std::string("unexpected token ") + quote(m_tokens[i]) + " after the " + what);
            }
        }
    }

private:
    std::istream& m_in;
    const std::string& m_name;
    std::string m_line;
    std::vector<std::string_view> m_tokens;
    std::size_t m_lineNo = 0;
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

}  // namespace

// -------------------------------------------------------------------------------------------------------------------
// OFF

TriangleMesh readOff(std::istream& in, const std::string& name) {
    const std::size_t remaining = remainingBytes(in);
    LineReader r(in, name);
    TriangleMesh mesh;

    if (!r.nextContent()) r.failAtEnd("empty file: expected the 'OFF' header or the vertex/face counts");
    std::size_t first = 0;
    if (isOffHeader(r.tokens()[0])) {
        first = 1;
        if (r.tokens().size() == 1) {
            if (!r.nextContent()) r.failAtEnd("unexpected end of file: expected the vertex/face counts");
            first = 0;
        }
    } else if (endsWithOff(r.tokens()[0])) {
        r.fail("unsupported OFF variant " + quote(r.tokens()[0]) + " (OFF, COFF, NOFF and CNOFF are read)");
    }

    // Counts: vertices faces [edges].
    const auto& ct = r.tokens();
    const std::size_t nCounts = ct.size() - first;
    if (nCounts < 2) {
        std::int64_t dummy = 0;
        bool overflow = false;
        if (first == 0 && !parseInt(ct[0], dummy, overflow) && !overflow) {
            r.fail("expected the 'OFF' header or the vertex/face counts, found " + quote(ct[0]));
        }
        r.fail("missing counts: expected 'vertices faces [edges]'");
    }
    if (nCounts > 3) r.fail("too many values on the counts line (expected 'vertices faces [edges]')");
    std::array<std::int64_t, 3> counts{0, 0, 0};
    for (std::size_t k = 0; k < nCounts; ++k) {
        counts[k] = r.integer(ct[first + k], "count");
        if (counts[k] < 0) r.fail("negative count " + quote(ct[first + k]));
    }
    const auto nv = static_cast<std::uint64_t>(counts[0]);
    const auto nf = static_cast<std::uint64_t>(counts[1]);
    if (nv > kMaxVertices) {
        r.fail("vertex count " + std::to_string(nv) + " is too large (at most " + std::to_string(kMaxVertices) +
               ")");
    }

    // "0 0 0\n" is the shortest vertex record, "3 0 0 0\n" the shortest face.
    mesh.vertices.reserve(boundedReserve(nv, remaining, 6));
    mesh.triangles.reserve(boundedReserve(nf, remaining, 8));

    for (std::uint64_t i = 0; i < nv; ++i) {
        if (!r.nextContent()) {
            r.failAtEnd("unexpected end of file: expected " + std::to_string(nv) + " vertices, found " +
                        std::to_string(i));
        }
        const auto& t = r.tokens();
        if (t.size() < 3) r.fail("vertex needs 3 coordinates, found " + std::to_string(t.size()));
        Vec3 p;
        for (int k = 0; k < 3; ++k) p[k] = r.number(t[static_cast<std::size_t>(k)], "vertex coordinate");
        r.checkTrailingNumbers(3, "vertex coordinates");
        mesh.vertices.push_back(p);
    }

    std::vector<std::uint32_t> polygon;
    for (std::uint64_t f = 0; f < nf; ++f) {
        if (!r.nextContent()) {
            r.failAtEnd("unexpected end of file: expected " + std::to_string(nf) + " faces, found " +
                        std::to_string(f));
        }
        const auto& t = r.tokens();
        const std::int64_t n = r.integer(t[0], "face vertex count");
        if (n < 3) r.fail("face has " + std::to_string(n) + " vertices (at least 3 are needed)");
        if (static_cast<std::uint64_t>(n) > t.size() - 1) {
            r.fail("face declares " + std::to_string(n) + " vertices but lists " + std::to_string(t.size() - 1));
        }
        polygon.clear();
        for (std::size_t k = 1; k <= static_cast<std::size_t>(n); ++k) {
            const std::int64_t idx = r.integer(t[k], "vertex index");
            if (idx < 0) r.fail("negative vertex index " + std::to_string(idx));
            if (static_cast<std::uint64_t>(idx) >= nv) {
                r.fail("vertex index " + std::to_string(idx) + " out of range (" + std::to_string(nv) +
                       " vertices)");
            }
            polygon.push_back(static_cast<std::uint32_t>(idx));
        }
        r.checkTrailingNumbers(static_cast<std::size_t>(n) + 1, "face indices (only a colour may follow)");
        addFan(mesh, polygon);
    }

    if (r.nextContent()) {
        r.fail("unexpected data after the last of the " + std::to_string(nf) + " declared faces: " +
               quote(r.tokens()[0]));
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

}  // namespace

TriangleMesh readObj(std::istream& in, const std::string& name) {
    LineReader r(in, name);
    TriangleMesh mesh;
    std::vector<std::uint32_t> polygon;
    // Faces that name a vertex defined further down (legal in OBJ): checked once all vertices are known.
    struct Pending {
        std::size_t line;
        std::uint64_t maxIndex;
    };
    std::vector<Pending> pending;

    while (r.nextContent()) {
        const auto& t = r.tokens();
        const std::string_view kw = t[0];
        if (kw == "v") {
            if (t.size() < 4) r.fail("vertex needs 3 coordinates, found " + std::to_string(t.size() - 1));
            if (mesh.vertices.size() >= kMaxVertices) r.fail("too many vertices");
            Vec3 p;
            for (int k = 0; k < 3; ++k) p[k] = r.number(t[static_cast<std::size_t>(k) + 1], "vertex coordinate");
            r.checkTrailingNumbers(4, "vertex coordinates");
            mesh.vertices.push_back(p);
        } else if (kw == "f") {
            if (t.size() < 4) {
                r.fail("face has " + std::to_string(t.size() - 1) + " vertices (at least 3 are needed)");
            }
            polygon.clear();
            std::uint64_t maxForward = 0;
            bool forward = false;
            const auto count = static_cast<std::int64_t>(mesh.vertices.size());
            for (std::size_t k = 1; k < t.size(); ++k) {
                const std::string_view ref = t[k];
                // v, v/vt, v//vn, v/vt/vn
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
                std::int64_t idx = 0;
                if (v == 0) {
                    r.fail("vertex index 0 is invalid (OBJ indices start at 1)");
                } else if (v < 0) {
                    idx = count + v;
                    if (idx < 0) {
                        r.fail("relative vertex index " + std::to_string(v) + " out of range (" +
                               std::to_string(count) + " vertices so far)");
                    }
                } else {
                    idx = v - 1;
                    if (static_cast<std::uint64_t>(idx) >= kMaxVertices) {
                        r.fail("vertex index " + std::to_string(v) + " out of range");
                    }
                    if (idx >= count) {
                        forward = true;
                        maxForward = std::max(maxForward, static_cast<std::uint64_t>(idx));
                    }
                }
                polygon.push_back(static_cast<std::uint32_t>(idx));
            }
            if (forward) pending.push_back({r.line(), maxForward});
            addFan(mesh, polygon);
        } else if (!isKeyword(kw)) {
            r.fail("unknown record " + quote(kw));
        }
        // Other records (vt, vn, g, o, s, usemtl, mtllib, l, ...) are ignored.
    }

    for (const Pending& p : pending) {
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

void openForReading(const std::string& path, std::ifstream& in) {
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) throw ParseError(path, 0, "file not found");
    if (!std::filesystem::is_regular_file(status)) throw ParseError(path, 0, "not a regular file");
    in.open(path, std::ios::binary);
    if (!in) throw ParseError(path, 0, "cannot open the file for reading");
}

}  // namespace

TriangleMesh readMesh(const std::string& path) {
    const std::string ext = lowerExtension(path);
    if (ext != ".off" && ext != ".obj") {
        throw ParseError(path, 0, "unsupported mesh format '" + ext + "' (.off and .obj are read)");
    }
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

std::vector<SceneObject> readSceneFile(const std::string& path) {
    std::ifstream in;
    openForReading(path, in);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw ParseError(path, 0, "read error");

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

    const std::filesystem::path baseDir = std::filesystem::path(path).parent_path();
    std::map<std::string, TriangleMesh> cache;  // a mesh used by several objects is read once
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
            // Problems with the reference itself are reported at the scene's line.
            std::error_code ec;
            const auto status = std::filesystem::status(meshFile, ec);
            if (ec || !std::filesystem::exists(status)) {
                throw ParseError(path, loc.lineOf(meshPos), where + ".mesh: file not found: " + meshFileName);
            }
            if (!std::filesystem::is_regular_file(status)) {
                throw ParseError(path, loc.lineOf(meshPos), where + ".mesh: not a regular file: " + meshFileName);
            }
            const std::string ext = lowerExtension(meshFileName);
            if (ext != ".off" && ext != ".obj") {
                throw ParseError(path, loc.lineOf(meshPos),
                                 where + ".mesh: unsupported mesh format '" + ext + "' (.off and .obj are read)");
            }
            // Errors inside the mesh name the mesh file and its line.
            cached = cache.emplace(meshFileName, readMesh(meshFileName)).first;
        }
        so.mesh = cached->second;

        const Eigen::Matrix3d linear = so.transform.topLeftCorner<3, 3>();
        const Eigen::Vector3d translation = so.transform.topRightCorner<3, 1>();
        for (std::size_t v = 0; v < so.mesh.vertices.size(); ++v) {
            Vec3& p = so.mesh.vertices[v];
            p = linear * p + translation;
            if (!p.allFinite()) {
                throw ParseError(path, loc.lineOf(trPos),
                                 where + ".transform maps vertex " + std::to_string(v) + " of " + so.meshPath +
                                     " to a non-finite point");
            }
        }
        scene.push_back(std::move(so));
    }
    return scene;
}

}  // namespace cullide::io
