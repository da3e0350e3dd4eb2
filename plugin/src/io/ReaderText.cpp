// ParseError and the text helpers shared by the readers (ReaderText.h): escaped, bounded names and tokens for
// error messages, strict whole-token number parsing.
#include "io/ReaderText.h"

#include "cullide/io/MeshIO.h"

#include <algorithm>
#include <charconv>
#include <limits>
#include <system_error>

namespace cullide::io {

namespace detail {

namespace {

/// Longest message shown in an error, in bytes; longer ones are cut.
constexpr std::size_t kMaxShownMessage = 1000;

}  // namespace

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

namespace {

/// Drops one leading '+' (from_chars takes none); false when nothing or another sign would be left.
bool dropLeadingPlus(std::string_view& s) {
    if (!s.empty() && s.front() == '+') {
        s.remove_prefix(1);
        if (s.empty() || s.front() == '+' || s.front() == '-') return false;
    }
    return !s.empty();
}

}  // namespace

bool parseDouble(std::string_view s, double& out) {
    if (!dropLeadingPlus(s)) return false;
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

bool parseInt(std::string_view s, std::int64_t& out, bool& overflow) {
    overflow = false;
    if (!dropLeadingPlus(s)) return false;
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

}  // namespace detail

namespace {

std::string formatParseError(const std::string& file, std::size_t line, const std::string& message) {
    std::string s = detail::printable(file, detail::kMaxShownName);
    if (line > 0) {
        s += ':';
        s += std::to_string(line);
    }
    s += ": ";
    s += detail::printable(message, detail::kMaxShownMessage);
    return s;
}

}  // namespace

ParseError::ParseError(const std::string& file, std::size_t line, const std::string& message)
    : std::runtime_error(formatParseError(file, line, message)), m_file(file), m_line(line) {}

}  // namespace cullide::io
