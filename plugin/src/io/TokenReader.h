// The token reader shared by the OFF and OBJ readers (plugin/src/io): whitespace-separated tokens read straight
// from the stream buffer, one record (line) at a time, with every byte checked for binary data. Also the limits
// and the polygon fan both mesh formats share.
#pragma once

#include "io/ReaderText.h"

#include "cullide/Types.h"
#include "cullide/io/MeshIO.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <istream>
#include <limits>
#include <streambuf>
#include <string>
#include <string_view>
#include <vector>

namespace cullide::io::detail {

/// Most vertices a mesh may have (its indices are 32-bit).
inline constexpr std::uint64_t kMaxVertices = std::numeric_limits<std::uint32_t>::max();

inline bool isSpace(int c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// Printable text, tabs and line-break characters, and bytes >= 0x80 (UTF-8 in comments and names) are text;
/// any other control byte means the input is not a text file.
inline bool isBinaryByte(unsigned char c) {
    return (c < 0x20 && c != '\t' && c != '\r' && c != '\v' && c != '\f' && c != '\n') || c == 0x7f;
}

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

/// Appends the polygon to `mesh` as a fan of triangles from its first vertex, in order.
inline void addFan(TriangleMesh& mesh, const std::vector<std::uint32_t>& polygon) {
    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
        mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
}

}  // namespace cullide::io::detail
