// JsonLocator (JsonLocator.h): a second, position-keeping pass over a JSON text nlohmann has accepted.
#include "io/JsonLocator.h"

#include "io/ReaderText.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace cullide::io::detail {

JsonLocator::JsonLocator(const std::string& text) : m_text(text) {
    for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] == '\n') m_newlines.push_back(i);
    }
    if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) m_start = 3;
}

std::size_t JsonLocator::lineOf(std::size_t pos) const {
    if (pos == npos) return 1;
    const auto before = std::lower_bound(m_newlines.begin(), m_newlines.end(), pos) - m_newlines.begin();
    return static_cast<std::size_t>(before) + 1;
}

std::size_t JsonLocator::member(std::size_t pos, std::string_view key) const {
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

std::size_t JsonLocator::element(std::size_t pos, std::size_t index) const {
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

std::size_t JsonLocator::firstOverflowingNumber() const {
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

std::size_t JsonLocator::skipWs(std::size_t i) const {
    while (i < m_text.size() &&
           (m_text[i] == ' ' || m_text[i] == '\t' || m_text[i] == '\n' || m_text[i] == '\r')) {
        ++i;
    }
    return i;
}

std::size_t JsonLocator::skipString(std::size_t i) const {
    ++i;
    while (i < m_text.size() && m_text[i] != '"') i += m_text[i] == '\\' ? 2 : 1;
    return std::min(i + 1, m_text.size());
}

std::size_t JsonLocator::scalarEnd(std::size_t i) const {
    while (i < m_text.size() && m_text[i] != ',' && m_text[i] != ']' && m_text[i] != '}' &&
           m_text[i] != ' ' && m_text[i] != '\t' && m_text[i] != '\n' && m_text[i] != '\r') {
        ++i;
    }
    return i;
}

std::size_t JsonLocator::skipValue(std::size_t i) const {
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

bool JsonLocator::keyEquals(std::size_t begin, std::size_t end, std::string_view key) const {
    const std::string_view raw = std::string_view(m_text).substr(begin + 1, end - begin - 2);
    if (raw.find('\\') == std::string_view::npos) return raw == key;
    try {
        return nlohmann::json::parse(m_text.substr(begin, end - begin)).get<std::string>() == key;
    } catch (const nlohmann::json::exception&) {
        return false;
    }
}

}  // namespace cullide::io::detail
