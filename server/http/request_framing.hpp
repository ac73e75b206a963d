// What the transport decides from a request's head before it reads a byte of
// the body (RFC 9112): where the request ends must be unambiguous, so that no
// body is ever read as the next request (request smuggling), and the target
// is brought to the origin-form the routes parse.
//
// Framing rules (checkFraming), each answered with `Connection: close`:
//  * HTTP/1.1 needs exactly one Host header (§3.2) → 400 otherwise;
//  * Transfer-Encoding in an HTTP/1.0 request → 400 (§6.1: faulty framing);
//  * Transfer-Encoding together with Content-Length → 400 (§6.3: ambiguous);
//  * Transfer-Encoding other than the single coding "chunked" (any case,
//    over one or several header lines: "chunked, gzip", "gzip, chunked",
//    "xchunked", "identity", "chunked;x=1") → 501, as nginx answers, since
//    no other coding is decoded here.
// Pure functions over plain values, so they are unit-tested and fuzzed
// without sockets.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tinsmith::server {

/// The facts of a request head that decide its framing.
struct RequestHead {
  int version = 11;                                 ///< 10 or 11
  std::vector<std::string_view> transferEncodings;  ///< each Transfer-Encoding line's value
  std::size_t contentLengths = 0;                   ///< Content-Length lines
  std::size_t hosts = 0;                            ///< Host lines
};

/// Why a request is refused: its status and the message for the client.
struct Refusal {
  int status = 400;
  std::string message;
};

/// nullopt when the head's framing is acceptable (see the file comment).
std::optional<Refusal> checkFraming(const RequestHead& head);

/// The origin-form of a request-target: an absolute-form target
/// ("http://host:8080/a/b?q", RFC 9112 §3.2.2, which a server must accept)
/// loses its scheme and authority ("/a/b?q"; "http://host" and
/// "http://host?q" become "/" and "/?q"); any other target is returned as it
/// is, for the route parser to judge. nullopt: an absolute-form target whose
/// scheme is not http or https, or that has no authority.
std::optional<std::string> originForm(std::string_view target);

}  // namespace tinsmith::server
