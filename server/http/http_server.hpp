// The HTTP/1.1 server: Boost.Beast's parser over Asio (chosen by measurement,
// docs/server-http-layer.md). One io_context per thread; one acceptor hands
// connections round-robin to the contexts; a connection lives on one
// context, so its handlers never run concurrently.
//
// Contracts:
//  * Limits: a request line longer than maxTargetBytes → 414; request line
//    and headers beyond maxHeaderBytes → 431 (414 when the request line alone
//    is over it); a body beyond maxBodyBytes → 413, counted over the chunks
//    of a chunked body; one chunk-size line (with its extensions) or the
//    trailer section beyond maxHeaderBytes → 431, so no part of a request
//    held in memory grows past its limit; a request that is not HTTP/1.x or
//    cannot be parsed → 400; framing that could be read two ways (Host,
//    Transfer-Encoding: request_framing.hpp) → 400 or 501, checked before
//    any of the body is read. Each of these closes the connection, after
//    draining what the client still sends for up to a second (a lingering
//    close, so the client reads the answer instead of a reset).
//  * Targets in absolute-form ("http://host/path") are served as their
//    origin-form ("/path"). Every response carries `Date`; the responses
//    the server makes itself (limits, timeouts, overload, 500) carry
//    ServerOptions::transportHeaders too (the app's CORS headers).
//  * Timeouts: the first request must arrive whole within readTimeout, each
//    later one on a keep-alive connection within idleTimeout; a response
//    must be written within writeTimeout. A request begun but not complete
//    at its deadline gets 408; an idle connection, or one whose write
//    expires, is closed (a slow client holds no thread: all I/O is
//    asynchronous).
//  * At most maxConnections open, and no more than the descriptor limit
//    (RLIMIT_NOFILE, whose soft value is raised toward the hard one as far
//    as needed) leaves room for, reservedDescriptors kept for stores, logs
//    and the rest (effectiveMaxConnections()). A connection over it gets 503
//    with `Connection: close`; when the process runs out of descriptors
//    anyway, a spare one is given up to answer that 503, so no newcomer
//    waits unanswered.
//  * The handler runs on the connection's thread and must be thread-safe.
//    An exception from it becomes a 500 with a JSON body (and is reported to
//    the observer like any response); the server never dies of one. A
//    response with `deferred` set is answered later, from elsewhere
//    (message.hpp): slow work leaves the I/O threads that way.
//  * stop() (thread-safe, callable from a signal handler's Asio callback):
//    no new connections; connections waiting for a request are closed;
//    requests being read, handled or written finish, answered with
//    `Connection: close`; run() returns when all are done, or after
//    shutdownGrace.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "server/http/message.hpp"

namespace tinsmith::server {

struct ServerLimits {
  std::size_t maxTargetBytes = 8 * 1024;
  std::size_t maxHeaderBytes = 16 * 1024;
  std::size_t maxBodyBytes = 1024 * 1024;
  std::size_t maxConnections = 10000;
  std::chrono::milliseconds readTimeout{10'000};
  std::chrono::milliseconds idleTimeout{30'000};
  std::chrono::milliseconds writeTimeout{30'000};
  std::chrono::milliseconds shutdownGrace{10'000};
  /// Descriptors kept free of connections, for store readers, logs and the
  /// server's own (see effectiveMaxConnections).
  std::size_t reservedDescriptors = 32;
};

struct ServerOptions {
  std::string host = "127.0.0.1";
  unsigned short port = 8080;  ///< 0: an ephemeral port (see HttpServer::port)
  int threads = 0;             ///< 0: one per core
  ServerLimits limits;
  /// Added to the responses the server makes itself (transport errors), as
  /// the handler adds them to its own: the app's CORS headers.
  std::vector<std::pair<std::string, std::string>> transportHeaders;
};

using Handler = std::function<Response(const Request&)>;
/// Called once per response, after it was written or the write failed.
using Observer = std::function<void(const Exchange&)>;
/// Called with +1 when a connection opens and -1 when it closes.
using ConnectionObserver = std::function<void(int)>;

class HttpServer {
 public:
  /// Binds and listens; throws ioError naming host:port when it cannot.
  HttpServer(ServerOptions options, Handler handler, Observer observer = {},
             ConnectionObserver connections = {});
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  /// The port listened on (the one the OS chose for port 0).
  [[nodiscard]] unsigned short port() const;
  /// The connections served at once: limits.maxConnections, or fewer when
  /// the descriptor limit leaves room for fewer (see the file comment).
  [[nodiscard]] std::size_t effectiveMaxConnections() const;
  /// Serves until stop(); runs the worker threads and joins them.
  void run();
  /// Begins the graceful shutdown (see the file comment). Thread-safe.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tinsmith::server
