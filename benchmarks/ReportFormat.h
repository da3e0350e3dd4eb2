// Number formatting and JSON access shared by the generated pages (ReportWriter: docs/benchmarks.md; SwapReport:
// docs/swap.md; Headline: the README's table of headline figures), so that a figure reads the same on every page.
#pragma once

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

namespace cullide::bench {

/// The engines a CULLIDE run is compared with (docs/benchmarks.md's "best peer": the fastest of them on the scene).
inline const std::set<std::string>& peerEngines() {
    static const std::set<std::string> peers = {"bullet-dbvt", "bullet-sap", "fcl", "fcl-aabb"};
    return peers;
}

inline nlohmann::json readJsonFile(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    try {
        return nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(path + ": " + e.what());
    }
}

/// The number under `key`, or nothing where it is absent or not a number.
inline std::optional<double> number(const nlohmann::json& j, const std::string& key) {
    const auto it = j.find(key);
    if (it == j.end() || !it->is_number()) return std::nullopt;
    return it->get<double>();
}

inline std::string fixed(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return buf;
}

/// Milliseconds with precision that suits their size.
inline std::string ms(double v) { return fixed(v, v < 1.0 ? 3 : v < 10.0 ? 2 : v < 100.0 ? 1 : 0); }

/// A whole number with thousands separators.
inline std::string count(double v) {
    std::string digits = std::to_string(static_cast<long long>(std::llround(v)));
    std::string out;
    const std::size_t n = digits.size();
    for (std::size_t i = 0; i < n; ++i) {
        out += digits[i];
        if (i + 1 < n && (n - i - 1) % 3 == 0 && digits[0] != '-') out += ',';
    }
    return out;
}

inline std::string ratio(double v) { return fixed(v, v < 0.1 ? 3 : 2) + "×"; }

/// Text safe inside a Markdown table cell.
inline std::string cell(std::string s) {
    for (std::size_t i = 0; (i = s.find('|', i)) != std::string::npos; i += 2) s.replace(i, 1, "\\|");
    return s;
}

/// "hardware GPU" or "CPU only (software GL)": the machine classes of the results files.
inline std::string classTitle(const std::string& c) {
    return c == "gpu" ? "hardware GPU" : "CPU only (software GL)";
}

}  // namespace cullide::bench
