// HTTP layer prototype (docs/server-http-layer.md): Debian's cpp-httplib 0.11
// tuned as issue 12 describes (a pool of 64 threads, TCP_NODELAY), answering
// every GET with the same in-memory body over keep-alive. Not part of the
// server; kept so the measurement can be repeated.
//   proto_httplib PORT BODY_BYTES THREADS
#include <httplib.h>

#include <cstdlib>
#include <iostream>
#include <string>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: proto_httplib PORT BODY_BYTES THREADS\n";
    return 2;
  }
  const std::string body(static_cast<std::size_t>(std::atol(argv[2])), 'x');
  const auto threads = static_cast<std::size_t>(std::atoi(argv[3]));
  httplib::Server server;
  server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  server.set_tcp_nodelay(true);
  server.set_keep_alive_max_count(1000000);
  server.Get("/.*", [&](const httplib::Request&, httplib::Response& res) {
    res.set_content(body, "application/octet-stream");
  });
  server.listen("127.0.0.1", std::atoi(argv[1]));
}
