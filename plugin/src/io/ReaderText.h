// Text helpers shared by the mesh and scene readers (plugin/src/io): bounded, escaped text for error messages and
// strict whole-token number parsing.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace cullide::io::detail {

/// Longest name (file path) shown in an error, in bytes; longer ones are cut.
inline constexpr std::size_t kMaxShownName = 200;

/// `s` for an error message: control bytes escaped (\0, \n, \t, \xNN), cut after `max` bytes (not inside a UTF-8
/// sequence) with the full size noted.
std::string printable(std::string_view s, std::size_t max);

/// Shortens a token for an error message (binary garbage can make tokens arbitrarily long and unprintable).
std::string quote(std::string_view token);

/// Parses a whole token as a decimal floating-point number (an optional '+' is accepted). Out-of-range values
/// that underflow become zero or subnormal; overflow makes the value infinite, which callers reject.
bool parseDouble(std::string_view s, double& out);

/// Parses a whole token as a decimal integer (an optional '+' is accepted).
bool parseInt(std::string_view s, std::int64_t& out, bool& overflow);

bool isInteger(std::string_view s, std::int64_t& out);

}  // namespace cullide::io::detail
