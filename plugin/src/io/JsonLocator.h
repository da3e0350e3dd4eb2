// Positions in a scene's JSON text (plugin/src/io/SceneReader.cpp): nlohmann::json keeps no source positions, so
// the scene reader finds where a value sits to give its semantic errors (a missing "mesh", a bad transform) a line.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace cullide::io::detail {

/// Finds where values sit in a JSON text that nlohmann has already accepted, to give semantic errors a line.
/// Offsets are byte offsets into the text; npos stands for "not found". Holds a reference to the text.
class JsonLocator {
public:
    static constexpr std::size_t npos = std::string::npos;

    explicit JsonLocator(const std::string& text);

    /// 1-based line of byte offset `pos` (npos: line 1).
    std::size_t lineOf(std::size_t pos) const;
    std::size_t root() const { return skipWs(m_start); }

    /// Offset of the value of member `key` in the object at `pos` (the last one when repeated), or npos.
    std::size_t member(std::size_t pos, std::string_view key) const;

    /// Offset of element `index` of the array at `pos`, or npos.
    std::size_t element(std::size_t pos, std::size_t index) const;

    /// Offset of the first number token that does not fit a double (nlohmann reports no position for those).
    std::size_t firstOverflowingNumber() const;

private:
    std::size_t skipWs(std::size_t i) const;
    /// `i` at the opening quote; returns the offset after the closing quote.
    std::size_t skipString(std::size_t i) const;
    std::size_t scalarEnd(std::size_t i) const;
    /// Iterative (nesting depth is unbounded in the input).
    std::size_t skipValue(std::size_t i) const;
    bool keyEquals(std::size_t begin, std::size_t end, std::string_view key) const;

    const std::string& m_text;
    std::vector<std::size_t> m_newlines;
    std::size_t m_start = 0;
};

}  // namespace cullide::io::detail
