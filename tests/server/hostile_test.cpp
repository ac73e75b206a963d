// What an attacker or a broken client sends: traversal in every encoding,
// absurd tile coordinates, oversized requests, garbage, slow and idle
// clients, clients that vanish mid-response, more connections than allowed —
// while another client keeps getting its tiles, byte for byte.
#include <gtest/gtest.h>

#include <atomic>
#include <random>

#include <nlohmann/json.hpp>

#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

/// Fetches one tile over and over on its own connection until stopped,
/// counting answers that are not the stored bytes.
class SteadyClient {
 public:
  explicit SteadyClient(unsigned short port)
      : expected_(store::openStoreForReading(testStoreDir() / "hill.3dtiles")->get("tiles/0/0/0.glb").value()),
        thread_([this, port] {
          HttpConnection c(port);
          while (!stop_.load()) {
            const auto r = c.request("/tilesets/hill/tiles/0/0/0.glb");
            ++fetched_;
            if (r.status != 200 || r.body != expected_) {
              ++wrong_;
              return;
            }
          }
        }) {}
  ~SteadyClient() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  /// Waits for at least `atLeast` answers (or a wrong one; at most 20 s),
  /// stops, and says whether every answer was right.
  ::testing::AssertionResult finish(int atLeast = 1) {
    for (int i = 0; i < 20000 && fetched_ < atLeast && wrong_ == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    stop_ = true;
    thread_.join();
    if (wrong_ > 0) return ::testing::AssertionFailure() << wrong_ << " wrong answers";
    if (fetched_ < atLeast) return ::testing::AssertionFailure() << "only " << fetched_ << " fetched";
    return ::testing::AssertionSuccess();
  }

 private:
  std::string expected_;
  std::atomic<bool> stop_{false};
  std::atomic<int> fetched_{0}, wrong_{0};
  std::thread thread_;
};

/// Sends raw bytes on a fresh connection and reads one response.
HttpResponse raw(unsigned short port, const std::string& bytes) {
  HttpConnection c(port);
  c.send(bytes);
  return c.read();
}

TEST(Hostile, TraversalInAnyEncodingNeverReachesAFile) {
  RunningServer server;
  SteadyClient steady(server.port());
  const std::string build =
      store::openStoreForReading(testStoreDir() / "hill.3dtiles")->get("tinsmith/build.json").value();
  for (const std::string target :
       {"/../../etc/passwd", "/tilesets/../tilesets/hill/tileset.json", "/tilesets/hill/../../etc/passwd",
        "/tilesets/hill/tinsmith/build.json", "/tilesets/hill/tinsmith/terrain.tin",
        "/tilesets/hill/%2e%2e/tinsmith/build.json", "/tilesets/%2E%2E/hill/tileset.json",
        "/tilesets/hill/tiles/..%2f..%2ftinsmith%2fbuild.json", "/tilesets/hill/tiles%2f0%2f0%2f0.glb",
        "/tilesets/hill/tiles/0/0/..%5c..%5cbuild.json", "/tilesets/hill%5c..%5ctileset.json",
        "/tilesets/%252e%252e/tileset.json", "/tilesets/hill/%252e%252e%252ftinsmith/build.json",
        "/tilesets/hill/tileset.json%00.glb", "/tilesets/hill%00/tileset.json", "/tilesets//hill/tileset.json",
        "/tilesets/./hill/tileset.json", "/tilesets/hill/tiles/0/0/0.glb/..", "//etc/passwd",
        "/tilesets/hill/tilesets/..%2f..%2ftinsmith%2fbuild.json", "/%c0%ae%c0%ae/etc/passwd"}) {
    const auto r = httpGet(server.port(), target);
    EXPECT_TRUE(r.status == 400 || r.status == 404) << target << " → " << r.status;
    EXPECT_EQ(r.header("content-type"), "application/json") << target;
    EXPECT_EQ(r.body.find("crc32"), std::string::npos) << target;  // nothing of build.json
  }
  // Raw bytes Beast itself refuses: a NUL, a space, a CR inside the target.
  for (const std::string& bad : {std::string("GET /tilesets\0/x HTTP/1.1\r\n\r\n", 29),
                                std::string("GET /a b HTTP/1.1\r\n\r\n"),
                                std::string("GET /a\rb HTTP/1.1\r\n\r\n")}) {
    const auto r = raw(server.port(), bad);
    EXPECT_EQ(r.status, 400);
  }
  EXPECT_NE(build.find("crc32"), std::string::npos);  // the marker the checks look for is real
  EXPECT_TRUE(steady.finish());
}

TEST(Hostile, AbsurdTileCoordinatesAreClientErrors) {
  RunningServer server;
  SteadyClient steady(server.port());
  for (const std::string zxy :
       {"-1/0/0", "0/-1/0", "0/0/-1", "a/0/0", "0/b/0", "0/0/c", "1.5/0/0", "0/0/0x1", "+1/0/0",
        "00/0/0", "99999999999999999999999999/0/0", "0/18446744073709551616/0", "4294967296/0/0",
        "1e3/0/0", "0/0/ 1", "%2d1/0/0"}) {
    const auto r = httpGet(server.port(), "/tilesets/hill/tiles/" + zxy + ".glb");
    EXPECT_EQ(r.status, 400) << zxy;
  }
  for (const std::string zxy : {"1/2/0", "1/0/2", "0/0/%31", "4294967295/0/0", "31/0/0", "30/1073741823/1073741823",
                                "4/15/15", "0/4294967295/4294967295"}) {
    const auto r = httpGet(server.port(), "/tilesets/hill/tiles/" + zxy + ".glb");
    EXPECT_EQ(r.status, 404) << zxy;
  }
  EXPECT_TRUE(steady.finish());
}

TEST(Hostile, OversizedRequestsGet414And431And413) {
  RunningServer server;
  SteadyClient steady(server.port());
  HttpConnection url(server.port());
  auto r = url.request("/tilesets/hill/elevation?x=" + std::string(9000, '1') + "&y=2");
  EXPECT_EQ(r.status, 414);
  EXPECT_EQ(r.header("connection"), "close");
  EXPECT_TRUE(url.closedByServer());
  r = httpGet(server.port(), "/" + std::string(40000, 'a'));  // beyond the header limit too
  EXPECT_EQ(r.status, 414);
  r = httpGet(server.port(), "/health", "X-Big: " + std::string(20000, 'b') + "\r\n");
  EXPECT_EQ(r.status, 431);
  std::string many;
  for (int i = 0; i < 2000; ++i) many += "X-H" + std::to_string(i) + ": v\r\n";
  EXPECT_EQ(httpGet(server.port(), "/health", many).status, 431);
  HttpConnection body(server.port());
  body.send("POST /tilesets/hill/elevation HTTP/1.1\r\nHost: x\r\nContent-Length: 5000000\r\n\r\n");
  EXPECT_EQ(body.read().status, 413);
  // A body on a GET is read (within the limit) and ignored.
  HttpConnection get(server.port());
  r = get.request("/tilesets/hill/tiles/0/0/0.glb", "", "GET", std::string(1000, 'x'));
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(get.request("/health").status, 200);  // and the connection stays in step
  EXPECT_TRUE(steady.finish());
}

TEST(Hostile, GarbageAndBadProtocolsAreRefused) {
  RunningServer server;
  SteadyClient steady(server.port());
  std::mt19937 rng(12);
  for (int round = 0; round < 50; ++round) {
    std::string junk(1 + rng() % 300, '\0');
    for (char& ch : junk) ch = static_cast<char>(rng());
    HttpConnection c(server.port(), 3000);
    c.send(junk + "\r\n\r\n");
    const auto r = c.read();
    EXPECT_TRUE(r.status == 0 || r.status == 400 || r.status == 414 || r.status == 505)
        << "round " << round << ": " << r.status;
  }
  const int http2 = raw(server.port(), "GET / HTTP/2.0\r\nHost: x\r\n\r\n").status;
  EXPECT_TRUE(http2 == 400 || http2 == 505) << http2;
  EXPECT_EQ(raw(server.port(), "GET / HTTX/1.1\r\n\r\n").status, 400);
  EXPECT_EQ(
      raw(server.port(), "GET /health HTTP/1.1\r\nHost: x\r\nContent-Length: -5\r\n\r\n").status,
      400);
  EXPECT_EQ(raw(server.port(),
                "GET /health HTTP/1.1\r\nHost: x\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n")
                .status,
            400);
  // Pipelined requests are answered in order.
  HttpConnection c(server.port());
  c.send("GET /health HTTP/1.1\r\nHost: x\r\n\r\nGET /tilesets/nope/tileset.json HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(c.read().status, 200);
  EXPECT_EQ(c.read().status, 404);
  EXPECT_TRUE(steady.finish());
}

TEST(Hostile, SlowAndIdleClientsAreCutOffWithoutStallingOthers) {
  auto options = RunningServer::defaults();
  options.http.limits.readTimeout = std::chrono::milliseconds(800);
  options.http.limits.idleTimeout = std::chrono::milliseconds(800);
  RunningServer server(options);
  SteadyClient steady(server.port());
  // A byte every 200 ms never makes a whole request in time: 408, closed.
  HttpConnection slow(server.port());
  const std::string request = "GET /tilesets/hill/tileset.json HTTP/1.1\r\nHost: x\r\n\r\n";
  for (char ch : request) {
    if (slow.anyArrived() || !slow.send(std::string(1, ch))) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  const auto r = slow.read();
  EXPECT_EQ(r.status, 408);
  // A connection that sends nothing is closed.
  HttpConnection idle(server.port());
  EXPECT_TRUE(idle.closedByServer());
  EXPECT_TRUE(steady.finish(5));
}

TEST(Hostile, AThousandIdleConnectionsDoNotStopService) {
  RunningServer server;
  SteadyClient steady(server.port());
  std::vector<std::unique_ptr<HttpConnection>> idle;
  for (int i = 0; i < 1000; ++i) {
    idle.push_back(std::make_unique<HttpConnection>(server.port()));
    ASSERT_TRUE(idle.back()->connected()) << i;
  }
  HttpConnection fresh(server.port());  // a newcomer is still served
  EXPECT_EQ(fresh.request("/tilesets/hill/tiles/0/0/0.glb").status, 200);
  const auto metrics = fresh.request("/metrics").body;
  const auto at = metrics.find("\ntinsmith_open_connections ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GE(std::stol(metrics.substr(at + 27)), 1000);
  idle.clear();
  EXPECT_TRUE(steady.finish());
}

TEST(Hostile, ConnectionsOverTheLimitGet503) {
  auto options = RunningServer::defaults();
  options.http.limits.maxConnections = 4;
  RunningServer server(options);
  std::vector<std::unique_ptr<HttpConnection>> held;
  for (int i = 0; i < 4; ++i) {
    held.push_back(std::make_unique<HttpConnection>(server.port()));
    EXPECT_EQ(held.back()->request("/health").status, 200);  // surely counted as open
  }
  HttpConnection extra(server.port());
  const auto r = extra.read();
  EXPECT_EQ(r.status, 503);
  EXPECT_EQ(r.header("connection"), "close");
  held.clear();
}

TEST(Hostile, ClientsVanishingMidResponseLeaveTheServerWhole) {
  RunningServer server;
  SteadyClient steady(server.port());
  std::string pipeline;
  for (int i = 0; i < 400; ++i) pipeline += "GET /tilesets/hill/tiles/0/0/0.glb HTTP/1.1\r\nHost: x\r\n\r\n";
  for (int round = 0; round < 20; ++round) {
    HttpConnection c(server.port());
    c.send(pipeline);  // megabytes of answers queue up behind a reader that never reads
    if (round % 2 == 0) c.readBytes(1000);  // or stops in the middle of one
    c.resetAndClose();  // RST: the server's pending write fails
  }
  EXPECT_EQ(httpGet(server.port(), "/health").status, 200);
  EXPECT_TRUE(steady.finish());
}

TEST(Hostile, AFailingStoreReadIsA500WithABodyAndALogLine) {
  namespace fs = std::filesystem;
  const auto broken = testStoreCopy("server-failing", "broken");
  fs::remove(broken / "tiles/0/0/0.glb");
  fs::create_symlink("0.glb", broken / "tiles/0/0/0.glb");  // a loop: open() fails with ELOOP

  auto options = RunningServer::defaults();
  options.stores = {broken};
  std::FILE* log = std::tmpfile();
  options.notices = log;
  RunningServer server(options);
  HttpConnection c(server.port());
  const auto r = c.request("/tilesets/broken/tiles/0/0/0.glb");
  EXPECT_EQ(r.status, 500);
  EXPECT_EQ(r.header("content-type"), "application/json");
  EXPECT_NE(r.body.find("\"status\":500"), std::string::npos) << r.body;
  EXPECT_EQ(r.body.find(broken.string()), std::string::npos) << r.body;  // no server paths
  EXPECT_EQ(c.request("/tilesets/broken/tileset.json").status, 200);  // and it goes on
  server.stopAndJoin();  // every exchange logged
  std::rewind(log);
  std::string text(4096, '\0');
  text.resize(std::fread(text.data(), 1, text.size(), log));
  std::fclose(log);
  EXPECT_NE(text.find("500 for"), std::string::npos) << text;
  EXPECT_NE(text.find("tiles/0/0/0.glb"), std::string::npos) << text;
}

TEST(Hostile, AStoreWithOddMetadataIsServedWithWhatItHas) {
  const auto path = testStoreCopy("server-odd", "odd");
  {
    auto odd = store::openStoreForWriting(path, true);
    odd->put("tinsmith/build.json", R"({"options": 5, "tin": [], "pyramid": {"origin": "x", "size": null}})");
    odd->put("tileset.json", R"({"asset": {"version": "1.1"}, "root": {"boundingVolume": {"box": [0,0,0,1,0,0,0,1,0,0,0,1]}}})");
    odd->put("tinsmith/terrain.tin", "not a TIN");
  }
  auto options = RunningServer::defaults();
  options.stores = {path};
  RunningServer server(options);
  const auto list = nlohmann::json::parse(httpGet(server.port(), "/tilesets").body);
  const auto& t = list["tilesets"][0];
  EXPECT_EQ(t["id"], "odd");
  EXPECT_EQ(t["crs"], "");
  EXPECT_FALSE(t["bounds"].contains("lonlat"));
  EXPECT_FALSE(t["bounds"].contains("project"));
  EXPECT_EQ(httpGet(server.port(), "/tilesets/odd/tiles/0/0/0.glb").status, 200);
  // The TIN cannot be read: the store's fault, a 500 (its details logged).
  EXPECT_EQ(httpGet(server.port(), "/tilesets/odd/elevation?x=430100&y=4515100").status, 500);
  EXPECT_EQ(httpGet(server.port(), "/tilesets/odd/profile?line=1,2;3,4").status, 500);
}

TEST(Hostile, AStoreWithoutItsTinHasNoElevations) {
  auto options = RunningServer::defaults();
  options.stores = {testStoreCopy("server-no-tin", "bare.3dtiles",
                                  [](const std::string& k) { return k != "tinsmith/terrain.tin"; })};
  RunningServer server(options);
  const auto e = httpGet(server.port(), "/tilesets/bare/elevation?x=430100&y=4515100");
  EXPECT_EQ(e.status, 404);
  EXPECT_NE(e.body.find("no TIN"), std::string::npos) << e.body;
  EXPECT_EQ(httpGet(server.port(), "/tilesets/bare/tiles/0/0/0.glb").status, 200);
}

}  // namespace
}  // namespace tinsmith::test
