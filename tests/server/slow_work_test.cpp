// Slow requests leave the I/O threads (server/app/work_pool.hpp): while an
// on-demand build and a large elevation batch are held up on the workers,
// the server's one I/O thread still answers /health, /metrics and cached
// tiles; a full queue answers 503 with Retry-After and a JSON body, and
// /metrics counts it. The slow work is held by the test itself: an
// exclusive SQLite lock on the archive, which the work's store reads wait
// behind (SQLite's busy timeout), released when the test has seen what it
// wants. So the order of the answers decides each test, never a clock:
// before the pool, the held request held the I/O thread, and /metrics did
// not answer until the lock was released.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <functional>
#include <future>

#include "ingest/store/tile_store.hpp"
#include "server/app/work_pool.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

bool aboveZoom2(const std::string& key) {
  return !key.starts_with("tiles/") || std::stoi(key.substr(6)) < 2;
}

/// An exclusive lock on an archive (rollback journal): every other
/// connection's read waits while it is held.
class ArchiveLock {
 public:
  explicit ArchiveLock(const std::filesystem::path& archive) {
    EXPECT_EQ(sqlite3_open(archive.c_str(), &db_), SQLITE_OK);
    EXPECT_EQ(sqlite3_exec(db_, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK);
  }
  ~ArchiveLock() { release(); }
  void release() {
    if (!db_) return;
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    sqlite3_close(db_);
    db_ = nullptr;
  }

 private:
  sqlite3* db_ = nullptr;
};

/// The value of one metric line ("name value") in /metrics, -1 when absent.
long long metric(unsigned short port, const std::string& name) {
  HttpConnection c(port, 3000);
  const std::string text = c.request("/metrics").body;
  const std::size_t at = text.find("\n" + name + " ");
  return at == std::string::npos ? -1 : std::stoll(text.substr(at + name.size() + 2));
}

/// Polls /metrics until `name` reads `value`; false when it does not within
/// 20 s, or /metrics stops answering (its I/O thread is held).
bool metricReaches(unsigned short port, const std::string& name, long long value) {
  for (int i = 0; i < 2000; ++i) {
    const long long now = metric(port, name);
    if (now == value) return true;
    if (now < 0 && i > 0) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

struct SlowServer {
  std::filesystem::path archive;
  std::map<std::string, std::string> deepTiles;  // key → the offline tiler's bytes
  std::unique_ptr<RunningServer> server;

  SlowServer(const std::string& name, std::size_t workers, std::size_t queue) {
    archive = testStoreCopy("server-slow-" + name, "slow.3dtiles", aboveZoom2);
    const auto full = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
    for (const auto& key : full->keys())
      if (!aboveZoom2(key)) deepTiles[key] = full->get(key).value();
    auto o = RunningServer::defaults();
    o.stores = {archive};
    o.service.onDemand = true;
    o.http.threads = 1;  // one I/O thread: whatever held it would hold every answer
    o.workers = workers;
    o.queue = queue;
    server = std::make_unique<RunningServer>(o);
  }
  [[nodiscard]] unsigned short port() const { return server->port(); }
  /// A deep tile's key (the n-th), which the store lacks and a build makes.
  [[nodiscard]] std::string deep(std::size_t n) const {
    auto it = deepTiles.begin();
    std::advance(it, static_cast<std::ptrdiff_t>(n));
    return it->first;
  }
};

std::string lonLatBatch(std::size_t n) {
  std::string body = "{\"crs\": \"lonlat\", \"points\": [";
  for (std::size_t i = 0; i < n; ++i)
    body += (i ? "," : "") + std::string("[-111.8") + std::to_string(10 + i % 80) + ", 40.7" +
            std::to_string(710 + i % 90) + "]";
  return body + "]}";
}

TEST(SlowWork, HealthAndCachedTilesAnswerWhileABuildAndABatchAreHeldOnTheWorkers) {
  SlowServer s("held", 2, 8);
  HttpConnection warm(s.port());
  ASSERT_EQ(warm.request("/tilesets/slow/tileset.json").status, 200);
  const auto cachedTile = warm.request("/tilesets/slow/tiles/0/0/0.glb");
  ASSERT_EQ(cachedTile.status, 200);
  const std::string batch = lonLatBatch(400);
  ASSERT_GE(batch.size(), server::kDeferBatchBytes);

  ArchiveLock lock(s.archive);
  HttpConnection build(s.port(), 20000), elevations(s.port(), 20000);
  ASSERT_TRUE(build.send("GET /tilesets/slow/" + s.deep(0) + " HTTP/1.1\r\nHost: x\r\n\r\n"));
  ASSERT_TRUE(
      elevations.send("POST /tilesets/slow/elevation HTTP/1.1\r\nHost: x\r\n"
                      "Content-Length: " +
                      std::to_string(batch.size()) + "\r\n\r\n" + batch));
  // Both on a worker, both waiting for the store behind the lock.
  ASSERT_TRUE(metricReaches(s.port(), "tinsmith_work_running", 2))
      << "/metrics did not answer while the slow requests were held";
  HttpConnection c(s.port(), 3000);
  const auto health = c.request("/health");
  EXPECT_EQ(health.status, 200);
  const auto tile = c.request("/tilesets/slow/tiles/0/0/0.glb");
  EXPECT_EQ(tile.status, 200);
  EXPECT_EQ(tile.body, cachedTile.body);
  EXPECT_EQ(c.request("/tilesets/slow/tileset.json").status, 200);
  // Answered while the held ones are not: the order is the proof.
  EXPECT_FALSE(build.anyArrived());
  EXPECT_FALSE(elevations.anyArrived());

  lock.release();
  const auto built = build.read();
  EXPECT_EQ(built.status, 200) << built.body;
  EXPECT_TRUE(built.body == s.deepTiles.at(s.deep(0))) << "not the offline tiler's bytes";
  EXPECT_EQ(built.header("access-control-allow-origin"), "*");
  const auto answered = elevations.read();
  ASSERT_EQ(answered.status, 200) << answered.body;
  const auto json = nlohmann::json::parse(answered.body);
  EXPECT_EQ(json["points"].size(), 400u);
  // The warming miss of tiles/0/0/0.glb went to a worker too (--on-demand).
  EXPECT_EQ(metric(s.port(), "tinsmith_work_queued_total"), 3);
  EXPECT_EQ(metric(s.port(), "tinsmith_work_rejected_total"), 0);
}

TEST(SlowWork, AFullQueueAnswers503WithRetryAfterAndTheMetricsCountIt) {
  SlowServer s("full", 1, 1);
  ArchiveLock lock(s.archive);
  HttpConnection running(s.port(), 20000), waiting(s.port(), 20000);
  ASSERT_TRUE(running.send("GET /tilesets/slow/" + s.deep(0) + " HTTP/1.1\r\nHost: x\r\n\r\n"));
  ASSERT_TRUE(metricReaches(s.port(), "tinsmith_work_running", 1));
  ASSERT_TRUE(waiting.send("GET /tilesets/slow/" + s.deep(1) + " HTTP/1.1\r\nHost: x\r\n\r\n"));
  ASSERT_TRUE(metricReaches(s.port(), "tinsmith_work_waiting", 1));

  HttpConnection c(s.port(), 3000);
  const auto refused = c.request("/tilesets/slow/" + s.deep(2), "Origin: https://a.example\r\n");
  EXPECT_EQ(refused.status, 503);
  EXPECT_EQ(refused.header("retry-after"), "1");
  EXPECT_EQ(refused.header("content-type"), "application/json");
  EXPECT_EQ(refused.header("access-control-allow-origin"), "*");
  const auto error = nlohmann::json::parse(refused.body, nullptr, false);
  ASSERT_TRUE(error.is_object()) << refused.body;
  EXPECT_EQ(error["error"]["status"], 503);
  // The connection stays usable, and cheap requests are still answered.
  EXPECT_EQ(c.request("/health").status, 200);
  EXPECT_EQ(metric(s.port(), "tinsmith_work_rejected_total"), 1);
  EXPECT_EQ(metric(s.port(), "tinsmith_work_queued_total"), 2);

  lock.release();
  const auto first = running.read(), second = waiting.read();
  EXPECT_EQ(first.status, 200);
  EXPECT_TRUE(first.body == s.deepTiles.at(s.deep(0)));
  EXPECT_EQ(second.status, 200);
  EXPECT_TRUE(second.body == s.deepTiles.at(s.deep(1)));
  // Asked again, the refused tile is built now.
  EXPECT_EQ(c.request("/tilesets/slow/" + s.deep(2)).status, 200);
}

TEST(SlowWork, ShutdownWaitsForTheRunningAndDropsTheWaiting) {
  server::WorkPool pool(1, 1);
  std::promise<void> started, release;
  auto gate = release.get_future().share();
  bool ran = false, waitingRan = false;
  ASSERT_TRUE(pool.trySubmit([&] {
    started.set_value();
    gate.wait();
    ran = true;
  }));
  started.get_future().wait();
  auto token = std::make_shared<int>(0);  // held by the waiting task only
  std::weak_ptr<int> watch = token;
  ASSERT_TRUE(pool.trySubmit([&, token] { waitingRan = true; }));
  token.reset();
  EXPECT_FALSE(pool.trySubmit([] {}));  // the queue holds one
  EXPECT_EQ(pool.stats().rejected, 1u);
  EXPECT_EQ(pool.stats().waiting, 1u);
  std::thread stopper([&] { pool.shutdown(); });
  while (!watch.expired()) std::this_thread::yield();  // the waiting task is dropped first
  release.set_value();
  stopper.join();
  EXPECT_TRUE(ran);
  EXPECT_FALSE(waitingRan);
  EXPECT_FALSE(pool.trySubmit([] {}));
}

}  // namespace
}  // namespace tinsmith::test
