#include "server/http/http_server.hpp"

#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange unincluded

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include <array>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>
#include <unordered_map>
#include <vector>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "server/http/error_status.hpp"

namespace tinsmith::server {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;

namespace {

std::string reasonPhrase(int status) {
  const auto reason = http::obsolete_reason(http::int_to_status(static_cast<unsigned>(status)));
  return reason.empty() ? std::string("Status") : std::string(reason);
}

/// The status line and headers of `r`; Content-Length always, from the body
/// slice (also for HEAD, which sends no body).
std::string serializeHead(const Response& r, bool keepAlive) {
  std::string out;
  out.reserve(256 + r.headers.size() * 48);
  out += "HTTP/1.1 ";
  out += std::to_string(r.status);
  out += ' ';
  out += reasonPhrase(r.status);
  out += "\r\n";
  for (const auto& [name, value] : r.headers) {
    out += name;
    out += ": ";
    out += value;
    out += "\r\n";
  }
  if (r.status != 304 && !(r.status >= 100 && r.status < 200) && r.status != 204) {
    out += "Content-Length: ";
    out += std::to_string(r.bodyLength());
    out += "\r\n";
  }
  out += keepAlive ? "Connection: keep-alive\r\n\r\n" : "Connection: close\r\n\r\n";
  return out;
}

/// A transport-level error (malformed or oversized request, overload).
Response transportError(int status, const std::string& message) {
  return errorResponse(status, status >= 500 ? ErrorKind::Internal : ErrorKind::Input, message);
}

}  // namespace

struct HttpServer::Impl {
  class Connection;

  ServerOptions options;
  Handler handler;
  Observer observer;
  ConnectionObserver connectionObserver;
  std::vector<std::unique_ptr<asio::io_context>> contexts;
  std::vector<asio::executor_work_guard<asio::io_context::executor_type>> guards;
  std::optional<tcp::acceptor> acceptor;
  std::optional<asio::steady_timer> acceptRetry;
  std::size_t nextContext = 0;
  std::atomic<bool> stopping{false};
  std::atomic<std::size_t> open{0};
  std::mutex mutex;  // guards connections, and stopRequested with `changed`
  std::condition_variable changed;
  bool stopRequested = false;
  std::unordered_map<Connection*, std::weak_ptr<Connection>> connections;

  void accept();
  void connectionOpened(const std::shared_ptr<Connection>& c);
  void connectionClosed(Connection* c);
};

class HttpServer::Impl::Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(Impl& server, tcp::socket socket, bool reject)
      : server_(server), stream_(std::move(socket)), reject_(reject) {
    beast::error_code ec;
    const auto remote = stream_.socket().remote_endpoint(ec);
    if (!ec) peer_ = remote.address().to_string() + ":" + std::to_string(remote.port());
    stream_.socket().set_option(tcp::no_delay(true), ec);
  }
  ~Connection() { server_.connectionClosed(this); }

  void start() {
    if (reject_) {
      respond(transportError(503, "the server has too many open connections; try again later"),
              false);
      return;
    }
    readRequest();
  }

  [[nodiscard]] auto executor() { return stream_.get_executor(); }

  /// Posted by stop(): closes the connection when it waits for a request
  /// and has received nothing of one (a body being read is a request in
  /// flight, though its bytes have left the buffer).
  void closeIfIdle() {
    if (state_ == State::Reading && buffer_.size() == 0 && !(parser_ && parser_->got_some())) {
      beast::error_code ec;
      stream_.socket().shutdown(tcp::socket::shutdown_both, ec);
      stream_.close();
    }
  }

 private:
  enum class State { Reading, Writing, Closed };

  void readRequest() {
    if (server_.stopping.load() && buffer_.size() == 0) return close();
    state_ = State::Reading;
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(server_.options.limits.maxHeaderBytes));
    parser_->body_limit(server_.options.limits.maxBodyBytes);
    stream_.expires_after(served_ == 0 ? server_.options.limits.readTimeout
                                       : server_.options.limits.idleTimeout);
    http::async_read_header(stream_, buffer_, *parser_,
                            [self = shared_from_this()](beast::error_code ec, std::size_t) {
                              self->onHeader(ec);
                            });
  }

  /// The header is in: a client waiting on `Expect: 100-continue` (curl
  /// does for bodies over 1 KiB) is told to go on, then the body is read.
  void onHeader(beast::error_code ec) {
    if (ec || parser_->is_done()) return onRead(ec);
    const auto& message = parser_->get();
    if (beast::iequals(message[http::field::expect], "100-continue") && message.version() == 11) {
      static constexpr std::string_view kContinue = "HTTP/1.1 100 Continue\r\n\r\n";
      asio::async_write(stream_, asio::buffer(kContinue.data(), kContinue.size()),
                        [self = shared_from_this()](beast::error_code e, std::size_t) {
                          if (e) return self->close();
                          self->readBody();
                        });
      return;
    }
    readBody();
  }

  void readBody() {
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) {
                       self->onRead(ec);
                     });
  }

  void onRead(beast::error_code ec) {
    started_ = std::chrono::steady_clock::now();
    if (ec == http::error::header_limit) {
      // 414 when the request line itself did not fit (the parser had not
      // got the target yet) or its target is too long, else 431.
      const std::size_t target = parser_->get().target().size();
      if (target == 0 || target > server_.options.limits.maxTargetBytes)
        return respond(transportError(414, "the request target is too long"), false);
      return respond(transportError(431, "the request headers are too large"), false);
    }
    if (ec == http::error::body_limit)
      return respond(transportError(413, "the request body is too large (at most " +
                                            std::to_string(server_.options.limits.maxBodyBytes) +
                                            " bytes)"),
                     false);
    if (ec == beast::error::timeout && (buffer_.size() > 0 || parser_->got_some()))
      return respond(transportError(408, "the request did not arrive in time"), false);
    if (ec == http::error::end_of_stream || ec == beast::error::timeout ||
        ec == asio::error::operation_aborted || ec == asio::error::connection_reset ||
        ec == asio::error::eof || ec == asio::error::bad_descriptor)
      return close();
    if (ec) return respond(transportError(400, "malformed HTTP request: " + ec.message()), false);

    auto& message = parser_->get();
    request_ = Request{};
    request_.method = std::string(message.method_string());
    request_.target = std::string(message.target());
    const bool keepAlive = message.keep_alive();
    if (request_.target.size() > server_.options.limits.maxTargetBytes)
      return respond(transportError(414, "the request target is too long"), false);
    if (message.version() != 10 && message.version() != 11)
      return respond(transportError(505, "only HTTP/1.0 and HTTP/1.1 are served"), false);
    const auto field = [&](http::field f) { return std::string(message[f]); };
    request_.ifNoneMatch = field(http::field::if_none_match);
    request_.range = field(http::field::range);
    request_.ifRange = field(http::field::if_range);
    request_.acceptEncoding = field(http::field::accept_encoding);
    request_.origin = field(http::field::origin);
    request_.contentType = field(http::field::content_type);
    request_.body = std::move(message.body());

    Response response;
    try {
      response = server_.handler(request_);
    } catch (const std::exception& e) {
      response = transportError(500, "the server failed to answer; its log has the details");
      response.failure = e.what();
    } catch (...) {
      response = transportError(500, "the server failed to answer; its log has the details");
      response.failure = "an exception that is not a std::exception";
    }
    if (response.deferred) return defer(std::move(response.deferred), keepAlive);
    respond(std::move(response), keepAlive);
  }

  /// The handler's answer comes later (Response::deferred): the connection
  /// reads nothing meanwhile and counts as busy (stop() lets it finish); the
  /// responder posts the answer back onto this connection's thread.
  void defer(std::function<void(Responder)> start, bool keepAlive) {
    state_ = State::Writing;
    auto self = shared_from_this();
    Responder responder = [self, keepAlive](Response answer) {
      asio::post(self->executor(), [self, keepAlive, answer = std::move(answer)]() mutable {
        self->respond(std::move(answer), keepAlive);
      });
    };
    try {
      start(std::move(responder));
    } catch (const std::exception& e) {
      Response failed = transportError(500, "the server failed to answer; its log has the details");
      failed.failure = e.what();
      respond(std::move(failed), false);
    }
  }

  void respond(Response response, bool keepAlive) {
    if (server_.stopping.load()) keepAlive = false;
    state_ = State::Writing;
    response_ = std::move(response);
    if (started_ == std::chrono::steady_clock::time_point{})
      started_ = std::chrono::steady_clock::now();
    head_ = serializeHead(response_, keepAlive);
    std::array<asio::const_buffer, 2> out{asio::buffer(head_), asio::const_buffer{}};
    if (response_.body && !response_.head && response_.status != 304)
      out[1] = asio::buffer(response_.body->data() + response_.offset, response_.bodyLength());
    stream_.expires_after(server_.options.limits.writeTimeout);
    asio::async_write(stream_, out,
                      [self = shared_from_this(), keepAlive](beast::error_code ec, std::size_t n) {
                        self->onWritten(ec, n, keepAlive);
                      });
  }

  void onWritten(beast::error_code ec, std::size_t bytes, bool keepAlive) {
    ++served_;
    if (server_.observer) {
      const Exchange exchange{request_, response_, peer_, bytes,
                              std::chrono::steady_clock::now() - started_, !ec};
      try {
        server_.observer(exchange);
      } catch (...) {  // a log line that cannot be written must not end the server
      }
    }
    response_ = Response{};
    started_ = {};
    if (ec || !keepAlive) return close();
    readRequest();
  }

  void close() {
    if (state_ == State::Closed) return;
    state_ = State::Closed;
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    stream_.close();
  }

  Impl& server_;
  beast::tcp_stream stream_;
  bool reject_ = false;
  State state_ = State::Reading;
  std::string peer_ = "-";
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  Request request_;
  Response response_;
  std::string head_;
  std::size_t served_ = 0;
  std::chrono::steady_clock::time_point started_{};
};

void HttpServer::Impl::accept() {
  auto& target = *contexts[nextContext];
  nextContext = (nextContext + 1) % contexts.size();
  acceptor->async_accept(target, [this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor->is_open()) return;
    if (ec) {  // out of descriptors and the like: wait a moment instead of spinning
      acceptRetry->expires_after(std::chrono::milliseconds(20));
      acceptRetry->async_wait([this](beast::error_code e) {
        if (!e && !stopping.load()) accept();
      });
      return;
    }
    const bool reject = open.load() >= options.limits.maxConnections;
    auto connection = std::make_shared<Connection>(*this, std::move(socket), reject);
    connectionOpened(connection);
    asio::post(connection->executor(), [connection] { connection->start(); });
    accept();
  });
}

void HttpServer::Impl::connectionOpened(const std::shared_ptr<Connection>& c) {
  ++open;
  {
    std::lock_guard lock(mutex);
    connections.emplace(c.get(), c);
  }
  if (connectionObserver) connectionObserver(+1);
}

void HttpServer::Impl::connectionClosed(Connection* c) {
  {
    std::lock_guard lock(mutex);
    connections.erase(c);
    --open;
  }
  changed.notify_all();
  if (connectionObserver) connectionObserver(-1);
}

HttpServer::HttpServer(ServerOptions options, Handler handler, Observer observer,
                       ConnectionObserver connections)
    : impl_(std::make_unique<Impl>()) {
  auto& m = *impl_;
  m.options = std::move(options);
  m.handler = std::move(handler);
  m.observer = std::move(observer);
  m.connectionObserver = std::move(connections);
  const int threads = static_cast<int>(resolveThreads(m.options.threads));
  for (int i = 0; i < threads; ++i) {
    m.contexts.push_back(std::make_unique<asio::io_context>(1));
    m.guards.push_back(asio::make_work_guard(*m.contexts.back()));
  }
  const std::string where = m.options.host + ":" + std::to_string(m.options.port);
  try {
    const tcp::endpoint endpoint(asio::ip::make_address(m.options.host), m.options.port);
    m.acceptor.emplace(*m.contexts[0]);
    m.acceptor->open(endpoint.protocol());
    m.acceptor->set_option(asio::socket_base::reuse_address(true));
    m.acceptor->bind(endpoint);
    m.acceptor->listen(asio::socket_base::max_listen_connections);
  } catch (const std::exception& e) {
    throw ioError("cannot listen on " + where + ": " + e.what(), {},
                  "choose another --host/--port, or stop what uses it");
  }
  m.acceptRetry.emplace(*m.contexts[0]);
  m.accept();
}

HttpServer::~HttpServer() {
  // Destroying a context destroys the connections its handlers hold, and they
  // unregister under the mutex: so the contexts go first, the mutex after.
  auto& m = *impl_;
  for (auto& c : m.contexts) c->stop();
  m.guards.clear();
  m.acceptRetry.reset();
  m.acceptor.reset();
  m.contexts.clear();
}

unsigned short HttpServer::port() const { return impl_->acceptor->local_endpoint().port(); }

void HttpServer::run() {
  auto& m = *impl_;
  std::vector<std::thread> workers;
  for (auto& context : m.contexts)
    workers.emplace_back([&c = *context] {
      for (;;) {
        try {
          c.run();
          return;
        } catch (...) {  // a handler escaped Asio: keep the thread serving
        }
      }
    });
  {
    std::unique_lock lock(m.mutex);
    m.changed.wait(lock, [&] { return m.stopRequested; });
    m.changed.wait_for(lock, m.options.limits.shutdownGrace, [&] { return m.open.load() == 0; });
  }
  for (auto& c : m.contexts) c->stop();
  for (auto& w : workers) w.join();
}

void HttpServer::stop() {
  auto& m = *impl_;
  if (m.stopping.exchange(true)) return;
  asio::post(*m.contexts[0], [&m] {
    beast::error_code ec;
    m.acceptor->close(ec);
    m.acceptRetry->cancel();
  });
  // Collected under the lock, released outside it: dropping the last
  // reference destroys a connection, which takes the lock.
  std::vector<std::shared_ptr<Impl::Connection>> open;
  {
    std::lock_guard lock(m.mutex);
    for (auto& [raw, weak] : m.connections)
      if (auto c = weak.lock()) open.push_back(std::move(c));
    m.stopRequested = true;
  }
  for (auto& c : open) asio::post(c->executor(), [c] { c->closeIfIdle(); });
  open.clear();
  for (auto& g : m.guards) g.reset();
  m.changed.notify_all();
}

}  // namespace tinsmith::server
