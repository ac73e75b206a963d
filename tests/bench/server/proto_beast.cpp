// HTTP layer prototype (docs/server-http-layer.md): Boost.Beast's parser over
// Asio, one io_context and one SO_REUSEPORT acceptor per thread, answering
// every GET with the same in-memory body over keep-alive. Not part of the
// server; kept so the measurement can be repeated.
//   proto_beast PORT BODY_BYTES THREADS
#include <utility>  // before Asio: Boost 1.74's awaitable.hpp uses std::exchange unincluded

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include <array>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace asio = boost::asio;
namespace http = boost::beast::http;
using tcp = asio::ip::tcp;

namespace {

struct Reply {
  std::string head, body;
};

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket socket, const Reply& reply) : socket_(std::move(socket)), reply_(reply) {}
  void start() { read(); }

 private:
  void read() {
    parser_.emplace();
    http::async_read(socket_, buffer_, *parser_,
                     [self = shared_from_this()](boost::beast::error_code ec, std::size_t) {
                       if (!ec) self->write();
                     });
  }
  void write() {
    const bool keep = parser_->get().keep_alive();
    std::array<asio::const_buffer, 2> out{asio::buffer(reply_.head), asio::buffer(reply_.body)};
    asio::async_write(socket_, out, [self = shared_from_this(), keep](boost::beast::error_code ec, std::size_t) {
      if (!ec && keep) self->read();
    });
  }
  tcp::socket socket_;
  boost::beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
  const Reply& reply_;
};

void accept(tcp::acceptor& acceptor, const Reply& reply) {
  acceptor.async_accept([&](boost::beast::error_code ec, tcp::socket socket) {
    if (!ec) {
      socket.set_option(tcp::no_delay(true));
      std::make_shared<Session>(std::move(socket), reply)->start();
    }
    accept(acceptor, reply);
  });
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: proto_beast PORT BODY_BYTES THREADS\n";
    return 2;
  }
  const auto port = static_cast<unsigned short>(std::atoi(argv[1]));
  Reply reply;
  reply.body.assign(static_cast<std::size_t>(std::atol(argv[2])), 'x');
  reply.head = "HTTP/1.1 200 OK\r\nContent-Type: application/octet-stream\r\nContent-Length: " +
               std::to_string(reply.body.size()) + "\r\n\r\n";
  const int threads = std::atoi(argv[3]);
  std::vector<std::thread> workers;
  for (int i = 0; i < threads; ++i) {
    workers.emplace_back([&] {
      asio::io_context io(1);
      tcp::acceptor acceptor(io);
      const tcp::endpoint endpoint(asio::ip::make_address("127.0.0.1"), port);
      acceptor.open(endpoint.protocol());
      acceptor.set_option(asio::socket_base::reuse_address(true));
      acceptor.set_option(asio::detail::socket_option::boolean<SOL_SOCKET, SO_REUSEPORT>(true));
      acceptor.bind(endpoint);
      acceptor.listen();
      accept(acceptor, reply);
      io.run();
    });
  }
  for (auto& w : workers) w.join();
}
