#include "server/http/http_server.hpp"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <cerrno>
#include <condition_variable>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>
#include <unordered_map>
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange unincluded
#include <vector>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "server/http/error_status.hpp"
#include "server/http/request_framing.hpp"

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

/// How long, and for how many bytes at most, a connection closed after an
/// error keeps reading what its client still sends (the lingering close).
/// Each read of it waits at most kLingerQuiet.
constexpr std::chrono::milliseconds kLinger{1000};
constexpr std::chrono::milliseconds kLingerQuiet{200};
constexpr std::size_t kLingerBytes = 1 << 20;

/// Now as an HTTP date, "Thu, 03 Dec 2026 12:48:13 GMT" (RFC 9110 §5.6.7),
/// formatted once a second per thread.
const std::string& httpDate() {
  thread_local std::time_t formatted = 0;
  thread_local std::string text;
  const std::time_t now = std::time(nullptr);
  if (now != formatted) {
    std::tm parts{};
    ::gmtime_r(&now, &parts);
    static constexpr const char* kDays[] = {"Sun", "Mon", "Tue", "Wed", "Thu", "Fri", "Sat"};
    static constexpr const char* kMonths[] = {"Jan", "Feb", "Mar", "Apr", "May", "Jun",
                                              "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};
    char out[40];
    std::snprintf(out, sizeof out, "%s, %02d %s %04d %02d:%02d:%02d GMT", kDays[parts.tm_wday],
                  parts.tm_mday, kMonths[parts.tm_mon], parts.tm_year + 1900, parts.tm_hour,
                  parts.tm_min, parts.tm_sec);
    text = out;
    formatted = now;
  }
  return text;
}

/// A descriptor held in reserve, given up to answer a 503 when the process
/// has none left (HttpServer::Impl::shedOneConnection).
int openSpareDescriptor() {
  return ::open("/dev/null", O_RDONLY | O_CLOEXEC);
}

/// The descriptors the process holds now.
std::size_t openDescriptors() {
  std::error_code ec;
  std::size_t n = 0;
  for (std::filesystem::directory_iterator it("/proc/self/fd", ec), end; !ec && it != end;
       it.increment(ec))
    ++n;
  return n;
}

/// How many connections fit under RLIMIT_NOFILE beside the descriptors open
/// now, `reserved` more and a spare: the soft limit is first raised toward
/// the hard one as far as `wanted` connections need.
std::size_t connectionsWithinDescriptorLimit(std::size_t wanted, std::size_t reserved) {
  rlimit limit{};
  if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) return wanted;
  const auto kept = static_cast<rlim_t>(openDescriptors() + reserved + 1);
  const rlim_t needed = kept + static_cast<rlim_t>(wanted);
  if (limit.rlim_cur != RLIM_INFINITY && limit.rlim_cur < needed) {
    rlimit raised = limit;
    raised.rlim_cur = limit.rlim_max == RLIM_INFINITY ? needed : std::min(needed, limit.rlim_max);
    if (::setrlimit(RLIMIT_NOFILE, &raised) == 0) limit = raised;
  }
  if (limit.rlim_cur == RLIM_INFINITY) return wanted;
  if (limit.rlim_cur <= kept) return 1;  // the spare descriptor still answers 503s
  return std::min(wanted, static_cast<std::size_t>(limit.rlim_cur - kept));
}

/// The framing facts of a parsed head (request_framing.hpp).
template <class Message>
RequestHead headOf(const Message& message) {
  RequestHead head;
  head.version = static_cast<int>(message.version());
  const auto codings = message.equal_range(http::field::transfer_encoding);
  for (auto it = codings.first; it != codings.second; ++it)
    head.transferEncodings.emplace_back(it->value().data(), it->value().size());
  head.contentLengths = message.count(http::field::content_length);
  head.hosts = message.count(http::field::host);
  return head;
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
  out += "\r\nDate: ";
  out += httpDate();
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
  std::size_t maxConnections = 0;  // within the descriptor limit
  int spareDescriptor = -1;        // given up to answer a 503 when out of descriptors

  /// A response the server makes itself (malformed or oversized request,
  /// timeout, overload), with the transport headers.
  [[nodiscard]] Response transportError(int status, const std::string& message) const {
    Response r =
        errorResponse(status, status >= 500 ? ErrorKind::Internal : ErrorKind::Input, message);
    if (status == 503) r.addHeader("Retry-After", "1");
    for (const auto& [name, value] : options.transportHeaders) r.addHeader(name, value);
    return r;
  }
  /// The 500 for a handler that threw; `failure` goes to the log only.
  [[nodiscard]] Response handlerFailure(std::string failure) const {
    Response r = transportError(500, "the server failed to answer; its log has the details");
    r.failure = std::move(failure);
    return r;
  }
  void accept();
  void acceptLater();
  /// Out of descriptors with a client waiting: gives up the spare one to
  /// accept it, answers 503 and closes; true when one was answered.
  bool shedOneConnection();
  void connectionOpened(const std::shared_ptr<Connection>& c);
  void connectionClosed(Connection* c);
};

class HttpServer::Impl::Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(Impl& server, tcp::socket socket, bool reject)
      : server_(server),
        stream_(std::move(socket)),
        deadline_(stream_.get_executor()),
        reject_(reject),
        buffer_(2 * std::max<std::size_t>(server.options.limits.maxHeaderBytes, 4096)) {
    beast::error_code ec;
    const auto remote = stream_.socket().remote_endpoint(ec);
    if (!ec) peer_ = remote.address().to_string() + ":" + std::to_string(remote.port());
    stream_.socket().set_option(tcp::no_delay(true), ec);
  }
  ~Connection() { server_.connectionClosed(this); }

  void start() {
    if (reject_) {
      respond(
          server_.transportError(503, "the server has too many open connections; try again later"),
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
    if (state_ == State::Lingering ||
        (state_ == State::Reading && buffer_.size() == 0 && !(parser_ && parser_->got_some()))) {
      beast::error_code ec;
      stream_.socket().shutdown(tcp::socket::shutdown_both, ec);
      stream_.close();
    }
  }

 private:
  enum class State { Reading, Writing, Lingering, Closed };

  // The buffer is bounded (twice the header limit), so a chunk-size line or
  // a trailer section that does not fit ends the read with buffer_overflow
  // instead of growing; Beast's header limit covers the head only.
  void readRequest() {
    if (server_.stopping.load() && buffer_.size() == 0) return close();
    state_ = State::Reading;
    parser_.emplace();
    parser_->header_limit(static_cast<std::uint32_t>(server_.options.limits.maxHeaderBytes));
    parser_->body_limit(server_.options.limits.maxBodyBytes);
    stream_.expires_never();
    armReadDeadline(served_ == 0 ? server_.options.limits.readTimeout
                                 : server_.options.limits.idleTimeout);
    http::async_read_header(stream_, buffer_, *parser_,
                            [self = shared_from_this()](beast::error_code ec, std::size_t) {
                              self->onHeader(ec);
                            });
  }

  /// The read deadline is our own timer, not the stream's: the stream's
  /// closes the socket, and a request begun by then is owed its 408.
  void armReadDeadline(std::chrono::milliseconds after) {
    timedOut_ = false;
    deadline_.expires_after(after);
    deadline_.async_wait([weak = weak_from_this()](beast::error_code ec) {
      if (ec) return;
      if (const auto self = weak.lock(); self && self->state_ == State::Reading) {
        self->timedOut_ = true;
        beast::error_code ignored;
        self->stream_.socket().cancel(ignored);
      }
    });
  }

  /// The header is in: its framing is checked before any body byte is read
  /// (request_framing.hpp); a client waiting on `Expect: 100-continue`
  /// (curl does for bodies over 1 KiB) is told to go on; then the body is
  /// read.
  void onHeader(beast::error_code ec) {
    if (!ec && !timedOut_) {
      const auto& head = parser_->get();
      std::optional<Refusal> refusal;
      if (head.version() != 10 && head.version() != 11)
        refusal = Refusal{505, "only HTTP/1.0 and HTTP/1.1 are served"};
      else
        refusal = checkFraming(headOf(head));
      if (refusal) {  // respond() cancels the deadline and starts the clock
        request_ = Request{};
        request_.method = std::string(head.method_string());
        request_.target = std::string(head.target());
        return respond(server_.transportError(refusal->status, refusal->message), false);
      }
    }
    if (ec || timedOut_ || parser_->is_done()) return onRead(ec);
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
    deadline_.cancel();
    started_ = std::chrono::steady_clock::now();
    const auto& limits = server_.options.limits;
    if (timedOut_) {
      if (buffer_.size() > 0 || parser_->got_some())
        return respond(
            server_.transportError(408, "the request did not arrive in time (within " +
                                            std::to_string(limits.readTimeout.count()) + " ms)"),
            false);
      return close();
    }
    if (ec == http::error::header_limit) {
      // 414 when the request line itself did not fit (the parser had not
      // got the target yet) or its target is too long, else 431.
      const std::size_t target = parser_->get().target().size();
      if (target == 0 || target > limits.maxTargetBytes)
        return respond(server_.transportError(414, "the request target is too long"), false);
      return respond(server_.transportError(431, "the request headers are too large"), false);
    }
    if (ec == http::error::body_limit)
      return respond(
          server_.transportError(413, "the request body is too large (at most " +
                                          std::to_string(limits.maxBodyBytes) + " bytes)"),
          false);
    if (ec == http::error::buffer_overflow)
      return respond(server_.transportError(431,
                                            "a chunk-size line or the trailers of the request are "
                                            "too large (at most " +
                                                std::to_string(limits.maxHeaderBytes) + " bytes)"),
                     false);
    if (ec == http::error::end_of_stream || ec == asio::error::operation_aborted ||
        ec == asio::error::connection_reset || ec == asio::error::eof ||
        ec == asio::error::bad_descriptor)
      return close();
    if (ec)
      return respond(server_.transportError(400, "malformed HTTP request: " + ec.message()), false);

    auto& message = parser_->get();
    request_ = Request{};
    request_.method = std::string(message.method_string());
    request_.target = std::string(message.target());
    const bool keepAlive = message.keep_alive();
    if (request_.target.size() > limits.maxTargetBytes)
      return respond(server_.transportError(414, "the request target is too long"), false);
    auto origin = originForm(request_.target);
    if (!origin)
      return respond(
          server_.transportError(400, "the request target is neither a path nor an http(s) URL"),
          false);
    request_.target = std::move(*origin);
    const auto field = [&](http::field f) { return std::string(message[f]); };
    request_.ifNoneMatch = field(http::field::if_none_match);
    request_.range = field(http::field::range);
    request_.ifRange = field(http::field::if_range);
    request_.accept = field(http::field::accept);
    request_.acceptEncoding = field(http::field::accept_encoding);
    request_.origin = field(http::field::origin);
    request_.contentType = field(http::field::content_type);
    request_.body = std::move(message.body());

    Response response;
    try {
      response = server_.handler(request_);
    } catch (const std::exception& e) {
      response = server_.handlerFailure(e.what());
    } catch (...) {
      response = server_.handlerFailure("an exception that is not a std::exception");
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
      respond(server_.handlerFailure(e.what()), false);
    }
  }

  void respond(Response response, bool keepAlive) {
    if (server_.stopping.load()) keepAlive = false;
    state_ = State::Writing;
    deadline_.cancel();
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
    if (ec) return close();
    if (!keepAlive) return lingeringClose();
    readRequest();
  }

  /// Closes our side for writing, then reads and drops what the client
  /// still sends (a body we refused, say) until it closes too, goes quiet
  /// for kLingerQuiet, kLinger has passed or kLingerBytes came: closing
  /// with unread bytes would reset the connection, and the client could
  /// lose the answer we just sent.
  void lingeringClose() {
    state_ = State::Lingering;
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    if (ec) return close();
    lingerLeft_ = kLingerBytes;
    lingerEnd_ = std::chrono::steady_clock::now() + kLinger;
    buffer_.clear();
    drain();
  }
  void drain() {
    const auto left = lingerEnd_ - std::chrono::steady_clock::now();
    if (left <= decltype(left)::zero()) return close();
    stream_.expires_after(std::min<std::chrono::steady_clock::duration>(left, kLingerQuiet));
    const std::size_t room = std::min<std::size_t>(buffer_.max_size(), 16 * 1024);
    stream_.async_read_some(buffer_.prepare(room),
                            [self = shared_from_this()](beast::error_code ec, std::size_t n) {
                              if (ec || n >= self->lingerLeft_ || self->state_ != State::Lingering)
                                return self->close();
                              self->lingerLeft_ -= n;
                              self->drain();
                            });
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
  asio::steady_timer deadline_;  // the read deadline (armReadDeadline)
  bool timedOut_ = false;
  std::size_t lingerLeft_ = 0;
  std::chrono::steady_clock::time_point lingerEnd_{};
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

void HttpServer::Impl::acceptLater() {
  acceptRetry->expires_after(std::chrono::milliseconds(20));  // a moment, instead of spinning
  acceptRetry->async_wait([this](beast::error_code e) {
    if (!e && !stopping.load()) accept();
  });
}

void HttpServer::Impl::accept() try {
  auto& target = *contexts[nextContext];
  nextContext = (nextContext + 1) % contexts.size();
  acceptor->async_accept(target, [this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor->is_open()) return;
    const bool outOfDescriptors = ec.value() == EMFILE || ec.value() == ENFILE;
    if (outOfDescriptors && shedOneConnection()) return accept();
    if (ec) return acceptLater();  // no spare descriptor, and the like
    const bool reject = open.load() >= maxConnections;
    auto connection = std::make_shared<Connection>(*this, std::move(socket), reject);
    connectionOpened(connection);
    asio::post(connection->executor(), [connection] { connection->start(); });
    accept();
  });
} catch (const std::exception&) {  // Asio out of memory or descriptors: accepting must go on
  acceptLater();
}

bool HttpServer::Impl::shedOneConnection() {
  if (spareDescriptor < 0) return false;
  ::close(spareDescriptor);
  const int client = ::accept4(acceptor->native_handle(), nullptr, nullptr, SOCK_CLOEXEC);
  if (client >= 0) {
    const Response r =
        transportError(503, "the server is out of file descriptors; try again later");
    const std::string answer = serializeHead(r, false) + *r.body;
    [[maybe_unused]] const auto sent =
        ::send(client, answer.data(), answer.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    ::shutdown(client, SHUT_WR);
    ::close(client);
  }
  spareDescriptor = openSpareDescriptor();
  return client >= 0 && spareDescriptor >= 0;
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
    // A timer makes the context's reactor now: made by its first connection
    // it would need descriptors the process may no longer have.
    asio::steady_timer reactorNow(*m.contexts.back());
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
  m.acceptor->non_blocking(true);  // shedOneConnection's accept4 must not wait
  m.acceptRetry.emplace(*m.contexts[0]);
  m.spareDescriptor = openSpareDescriptor();
  m.maxConnections = connectionsWithinDescriptorLimit(m.options.limits.maxConnections,
                                                      m.options.limits.reservedDescriptors);
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
  if (m.spareDescriptor >= 0) ::close(m.spareDescriptor);
}

unsigned short HttpServer::port() const { return impl_->acceptor->local_endpoint().port(); }

std::size_t HttpServer::effectiveMaxConnections() const {
  return impl_->maxConnections;
}

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
