// The request-target of an HTTP request ("/tilesets/rb/tiles/3/2/5.glb?x=1")
// parsed into decoded path segments and query parameters, strictly: the
// server never joins what a client sends into a file path, and this parser
// refuses anything a route could not mean, so routes see clean values only.
//
// Path (origin-form only, RFC 9112 3.2.1): starts with '/', split on '/';
// each segment percent-decoded once. Refused (nullopt): a target not starting
// with '/', a bad escape ("%4", "%zz"), an escape that decodes to '/', '\\',
// NUL or any control byte, a raw control byte or '\\', a "." or ".." segment
// (raw or decoded), an empty segment other than a single trailing one, more
// than kMaxSegments segments. A decoded segment is never decoded again, so
// "%252e%252e" is the literal text "%2e%2e", which names nothing.
//
// Query: '&'-separated "name=value" pairs, '+' and percent escapes decoded
// once; a bad escape or a decoded control byte is refused; a pair without
// '=' has an empty value; at most kMaxParameters pairs.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tinsmith::server {

inline constexpr std::size_t kMaxSegments = 16;
inline constexpr std::size_t kMaxParameters = 32;

struct RequestTarget {
  std::vector<std::string> segments;  ///< decoded; "/" gives none
  bool trailingSlash = false;         ///< "/a/b/" (not for "/")
  std::vector<std::pair<std::string, std::string>> query;  ///< decoded, in order

  /// The value of the first parameter `name`, or nullopt.
  [[nodiscard]] std::optional<std::string_view> parameter(std::string_view name) const;
};

/// Parses a request-target; nullopt when it is malformed (see the file comment).
std::optional<RequestTarget> parseRequestTarget(std::string_view target);

/// A finite double written in full (optional sign, digits, '.', exponent;
/// no spaces, no "inf"/"nan", no hex), or nullopt.
std::optional<double> parseFiniteDouble(std::string_view text);

/// A non-negative decimal integer without sign or leading zeros (but "0")
/// that fits in `unsigned long long` and is at most `max`, or nullopt.
std::optional<unsigned long long> parseBoundedUnsigned(std::string_view text,
                                                       unsigned long long max);

}  // namespace tinsmith::server
