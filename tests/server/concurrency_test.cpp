// Many clients at once: 48 connections fetch every tile and tileset file of
// the store in their own order; every byte matches the store and the metrics
// count exactly the requests made. And the graceful shutdown: a request in
// flight is answered, an idle connection is closed, run() returns, and the
// CLI exits 0 on SIGTERM.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <random>
#include <fstream>

#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

TEST(Concurrency, ParallelClientsGetEveryByteAndTheMetricsAddUp) {
  const auto store = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  std::vector<std::pair<std::string, std::string>> files;  // key, bytes
  std::size_t tiles = 0;
  for (const auto& key : store->keys()) {
    if (key.starts_with("tinsmith/")) continue;  // not served
    files.emplace_back(key, store->get(key).value());
    tiles += key.starts_with("tiles/");
  }
  ASSERT_GE(tiles, 5u);

  auto options = RunningServer::defaults();
  options.service.cacheBytes = 1 << 20;  // small: hits, misses and evictions all happen
  RunningServer server(options);
  constexpr int kClients = 48;
  std::atomic<int> wrong{0};
  std::vector<std::thread> clients;
  for (int k = 0; k < kClients; ++k) {
    clients.emplace_back([&, k] {
      std::vector<std::size_t> order(files.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::shuffle(order.begin(), order.end(), std::mt19937(static_cast<unsigned>(k)));
      HttpConnection c(server.port());
      for (std::size_t i : order) {
        const auto r = c.request("/tilesets/hill/" + files[i].first);
        if (r.status != 200 || r.body != files[i].second) ++wrong;
      }
      if (c.request("/health").status != 200) ++wrong;
    });
  }
  for (auto& t : clients) t.join();
  EXPECT_EQ(wrong.load(), 0);
  // Once run() has returned every response has been counted (a response is
  // counted after it is written, which a client may see first).
  server.stopAndJoin();

  const auto& m = server.server().metrics();
  EXPECT_EQ(m.requests(server::RouteKind::Tile, 200), kClients * tiles);
  EXPECT_EQ(m.requests(server::RouteKind::TilesetJson, 200) +
                m.requests(server::RouteKind::ExternalTileset, 200),
            kClients * (files.size() - tiles));
  EXPECT_EQ(m.requests(server::RouteKind::Health, 200), static_cast<std::uint64_t>(kClients));
  const std::string text = m.prometheusText();
  const auto count = [&](const std::string& name) {
    const auto at = text.find("\n" + name + " ");
    return at == std::string::npos ? -1.0 : std::stod(text.substr(at + name.size() + 2));
  };
  EXPECT_EQ(count("tinsmith_tile_cache_hits_total") + count("tinsmith_tile_cache_misses_total"),
            static_cast<double>(kClients * files.size()));
  EXPECT_GT(count("tinsmith_tile_cache_hits_total"), 0);
  EXPECT_EQ(count("tinsmith_http_request_duration_seconds_count"),
            static_cast<double>(kClients * (files.size() + 1)));
}

TEST(Shutdown, InFlightRequestsFinishIdleConnectionsCloseAndRunReturns) {
  RunningServer server;
  const unsigned short port = server.port();
  HttpConnection busy(port);
  ASSERT_EQ(busy.request("/health").status, 200);
  HttpConnection idle(port);
  ASSERT_EQ(idle.request("/health").status, 200);
  // Half a request: the server has bytes of it when the shutdown begins (a
  // second is ample for it to read them; nothing is asserted about time).
  ASSERT_TRUE(busy.send("GET /tilesets/hill/tileset.json HTTP/1.1\r\nHost: x\r\n"));
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  std::thread stopper([&] { server.stopAndJoin(); });
  EXPECT_TRUE(idle.closedByServer());
  ASSERT_TRUE(busy.send("\r\n"));
  const auto r = busy.read();
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.header("connection"), "close");
  stopper.join();  // run() returned
  HttpConnection late(port);
  EXPECT_FALSE(late.connected());
}

TEST(Shutdown, TheCliExitsZeroOnSigterm) {
  const auto dir = scratchDir("serve-cli-" + std::to_string(::getpid()));
  const auto script = dir / "serve.sh";
  {
    std::ofstream out(script);
    out << "log=" << (dir / "log").string() << "\n"
        << TINSMITH_BINARY << " serve " << (testStoreDir() / "hill.3dtiles").string()
        << " --port 0 2>$log &\n"
        << "pid=$!\n"
           "for i in $(seq 200); do grep -q 'http://' $log && break; sleep 0.05; done\n"
           "port=$(sed -n 's|.*http://127.0.0.1:\\([0-9]*\\)/.*|\\1|p' $log)\n"
           "exec 3<>/dev/tcp/127.0.0.1/$port\n"
           "printf 'GET /health HTTP/1.1\\r\\nHost: x\\r\\nConnection: close\\r\\n\\r\\n' >&3\n"
           "head -n 1 <&3\n"
           "exec 3<&-\n"
           "kill -TERM $pid\n"
           "wait $pid\n"
           "echo \"exit=$?\"\n"
           "cat $log\n";
  }
  const auto r = runCommand("timeout 60 bash " + script.string());
  EXPECT_NE(r.out.find("HTTP/1.1 200 OK"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("exit=0"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("\"GET /health\" 200"), std::string::npos) << r.out;  // the access log
  EXPECT_NE(r.out.find("stopped"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace tinsmith::test
