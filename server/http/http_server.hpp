// The HTTP/1.1 server: Boost.Beast's parser over Asio (chosen by measurement,
// docs/server-http-layer.md). One io_context per thread; one acceptor hands
// connections round-robin to the contexts; a connection lives on one
// context, so its handlers never run concurrently.
//
// Contracts:
//  * Limits: a request line longer than maxTargetBytes → 414; request line
//    and headers beyond maxHeaderBytes → 431 (414 when the request line alone
//    is over it); a body beyond maxBodyBytes → 413; a request that is not
//    HTTP/1.x or cannot be parsed → 400. Each of these closes the connection.
//  * Timeouts: the first request must arrive whole within readTimeout, each
//    later one on a keep-alive connection within idleTimeout; a response
//    must be written within writeTimeout. On expiry the connection is closed
//    (a slow client holds no thread: all I/O is asynchronous).
//  * At most maxConnections open; a connection over it gets 503 with
//    `Connection: close` and is closed.
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
};

struct ServerOptions {
  std::string host = "127.0.0.1";
  unsigned short port = 8080;  ///< 0: an ephemeral port (see HttpServer::port)
  int threads = 0;             ///< 0: one per core
  ServerLimits limits;
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
  /// Serves until stop(); runs the worker threads and joins them.
  void run();
  /// Begins the graceful shutdown (see the file comment). Thread-safe.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tinsmith::server
