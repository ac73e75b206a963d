// What the HTTP server hands a handler and takes back: plain values, no
// Boost types, so routes are tested and fuzzed without sockets.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "server/http/route.hpp"

namespace tinsmith::server {

/// A parsed request: the method as sent, the raw target, the request headers
/// the routes read (empty when absent) and the body.
struct Request {
  std::string method;  ///< "GET", "HEAD", … (case-sensitive, RFC 9110 9.1)
  std::string target;
  std::string ifNoneMatch, range, ifRange, accept, acceptEncoding, origin, contentType;
  std::string body;
};

struct Response;
/// Delivers a deferred response (see Response::deferred): call it once, from
/// any thread.
using Responder = std::function<void(Response)>;

/// A response. `body` is shared so cached content is sent without a copy;
/// [offset, offset + length) of it goes out (a 206's range), all of it when
/// length is npos. `head` sends the headers with the body's Content-Length
/// and no body. `route` labels the metrics and the access log.
struct Response {
  int status = 200;
  std::vector<std::pair<std::string, std::string>> headers;
  std::shared_ptr<const std::string> body;
  std::size_t offset = 0, length = std::string::npos;
  bool head = false;
  RouteKind route = RouteKind::Unknown;
  bool cacheHit = false;  ///< the tile came from the memory cache
  /// For a 5xx: what went wrong, for the server's log (the client gets a
  /// generic message, without paths or internals).
  std::string failure;
  /// Set: the answer comes later, and the rest of this response is ignored.
  /// The server calls it once, on the connection's thread right after the
  /// handler returned, with a Responder that writes the answer it is given
  /// on the connection's thread; meanwhile the connection reads nothing
  /// more. It is how a handler moves slow work off the I/O threads (a
  /// worker pool: server/app/work_pool.hpp). A responder that is destroyed
  /// uncalled closes the connection unanswered.
  std::function<void(Responder)> deferred;

  [[nodiscard]] std::size_t bodyLength() const {
    if (!body) return 0;
    return length == std::string::npos ? body->size() - offset : length;
  }
  void setBody(std::string bytes) { body = std::make_shared<const std::string>(std::move(bytes)); }
  void addHeader(std::string name, std::string value) {
    headers.emplace_back(std::move(name), std::move(value));
  }
};

/// What happened to one request, after its response was written (or failed).
struct Exchange {
  const Request& request;
  const Response& response;
  std::string_view peer;        ///< "127.0.0.1:53122"
  std::size_t bytesWritten = 0;  ///< headers and body
  std::chrono::steady_clock::duration elapsed{};
  bool completed = false;  ///< false: the client went away or the write timed out
};

}  // namespace tinsmith::server
