// An archive renamed over while it is served (a new version of the store)
// is not mixed into the old one: every connection of a store opened for
// reading stays on the file the store opened, so until the server reloads,
// 32 concurrent requests all get the old bytes with the old ETag, and after
// the reload (TileServer::reload, as SIGHUP and --reload do) all get the new.
// And SIGHUP reloads `tinsmith serve` (it used to kill it): a store copied
// into the served folder is served at once, with --reload 0, and the
// process goes on.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;

constexpr int kClients = 32;

/// Runs f(i) for i in [0, kClients) on kClients threads started together.
template <class F>
void together(F&& f) {
  std::atomic<int> ready{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < kClients; ++i)
    threads.emplace_back([&, i] {
      ++ready;
      while (ready < kClients) std::this_thread::yield();
      f(i);
    });
  for (auto& t : threads) t.join();
}

TEST(ArchiveReplacement, AStoreReadsOnlyTheFileItOpened) {
  const auto dir = scratchDir("archive-replaced-" + std::to_string(::getpid()));
  const auto live = dir / "live.3dtiles";
  fs::copy_file(testStoreDir() / "hill.3dtiles", live);
  const auto reader = store::openStoreForReading(live);
  const auto old = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  const std::string oldTileset = old->get("tileset.json").value();
  fs::copy_file(coarseStore(), dir / "next.3dtiles");
  fs::rename(dir / "next.3dtiles", live);
  ASSERT_NE(store::openStoreForReading(live)->get("tileset.json").value(), oldTileset);

  std::atomic<int> wrong{0};
  together([&](int) {
    for (int k = 0; k < 20; ++k)
      if (reader->get("tileset.json") != oldTileset) ++wrong;
  });
  EXPECT_EQ(wrong.load(), 0) << "reads of the file renamed over the one the store opened";
}

TEST(ArchiveReplacement, ConcurrentAnswersAreAllOldUntilTheReloadThenAllNew) {
  const auto dir = scratchDir("archive-replaced-server-" + std::to_string(::getpid()));
  const auto live = dir / "live.3dtiles";
  fs::copy_file(testStoreDir() / "hill.3dtiles", live);
  auto options = RunningServer::defaults();
  options.stores = {live};
  options.reloadInterval = std::chrono::milliseconds(0);  // --reload 0: only on demand
  options.service.cacheBytes = 0;                         // every answer read from the store
  options.http.threads = 8;  // reads side by side, so the store opens more connections
  RunningServer server(options);
  const auto before = httpGet(server.port(), "/tilesets/live/tileset.json");
  ASSERT_EQ(before.status, 200);

  fs::copy_file(coarseStore(), dir / "next.3dtiles");
  fs::rename(dir / "next.3dtiles", live);
  const std::string newTileset =
      store::openStoreForReading(coarseStore())->get("tileset.json").value();
  ASSERT_NE(newTileset, before.body);

  std::atomic<int> oldAnswers{0}, newAnswers{0};
  std::string newEtag;
  std::mutex etagMutex;
  constexpr int kRequests = 10;  // each client's, on one connection
  const auto ask = [&](int) {
    HttpConnection c(server.port());
    for (int k = 0; k < kRequests; ++k) {
      const auto r = c.request("/tilesets/live/tileset.json");
      if (r.status == 200 && r.body == before.body && r.header("etag") == before.header("etag"))
        ++oldAnswers;
      if (r.status == 200 && r.body == newTileset) {
        ++newAnswers;
        std::lock_guard lock(etagMutex);
        newEtag = r.header("etag");
      }
    }
  };
  together(ask);
  EXPECT_EQ(oldAnswers.load(), kClients * kRequests)
      << newAnswers << " answers were the new store's";

  const auto lines = server.server().reload();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("reloaded"), std::string::npos) << lines[0];
  oldAnswers = 0;
  newAnswers = 0;
  together(ask);
  EXPECT_EQ(newAnswers.load(), kClients * kRequests)
      << oldAnswers << " answers were the old store's";
  EXPECT_NE(newEtag, before.header("etag"));
}

TEST(ArchiveReplacement, ATileBuiltFromTheOldStoreIsNotWrittenIntoTheNewOne) {
  const auto dir = scratchDir("archive-replaced-keep-" + std::to_string(::getpid()));
  const auto live = dir / "live.3dtiles";
  {
    const auto source = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
    std::vector<std::string> keys;
    for (const auto& k : source->keys())
      if (!k.starts_with("tiles/") || std::stoi(k.substr(6)) < 2) keys.push_back(k);
    store::writeStore(*source, keys, live);
  }
  const auto coarse = store::openStoreForReading(coarseStore());
  std::string missing;  // a deep tile of the old store that the new one lacks
  for (const auto& k : store::openStoreForReading(testStoreDir() / "hill.3dtiles")->keys())
    if (k.starts_with("tiles/") && std::stoi(k.substr(6)) >= 2 && !coarse->contains(k)) missing = k;
  ASSERT_FALSE(missing.empty());

  auto options = RunningServer::defaults();
  options.stores = {live};
  options.reloadInterval = std::chrono::milliseconds(0);
  options.service.onDemand = true;
  RunningServer server(options);
  ASSERT_EQ(httpGet(server.port(), "/tilesets/live/tileset.json").status, 200);
  fs::copy_file(coarseStore(), dir / "next.3dtiles");
  fs::rename(dir / "next.3dtiles", live);
  EXPECT_EQ(httpGet(server.port(), "/tilesets/live/" + missing).status, 200);
  EXPECT_FALSE(store::openStoreForReading(live)->contains(missing))
      << "the old store's tile was written into the archive renamed over it";
}

TEST(ArchiveReplacement, SighupReloadsTheCliAndItGoesOnServing) {
  const auto dir = scratchDir("serve-sighup-" + std::to_string(::getpid()));
  fs::create_directories(dir / "stores");
  fs::copy_file(testStoreDir() / "hill.3dtiles", dir / "stores" / "first.3dtiles");
  const auto script = dir / "serve.sh";
  {
    std::ofstream out(script);
    out << "log=" << (dir / "log").string() << "\n"
        << TINSMITH_BINARY << " serve " << (dir / "stores").string()
        << " --port 0 --reload 0 2>$log &\n"
        << "pid=$!\n"
           "for i in $(seq 400); do grep -q 'http://' $log && break; sleep 0.05; done\n"
           "port=$(sed -n 's|.*http://127.0.0.1:\\([0-9]*\\)/.*|\\1|p' $log)\n"
           "list() {\n"
           "  exec 3<>/dev/tcp/127.0.0.1/$port\n"
           "  printf 'GET /tilesets HTTP/1.1\\r\\nHost: x\\r\\nConnection: close\\r\\n\\r\\n' >&3\n"
           "  cat <&3\n"
           "  exec 3<&-\n"
           "}\n"
        << "cp " << coarseStore().string() << " " << (dir / "second.tmp").string() << "\n"
        << "mv " << (dir / "second.tmp").string() << " "
        << (dir / "stores" / "second.3dtiles").string()
        << "\n"
           "list | grep -c '\"id\": \"second\"' | sed 's/^/before=/'\n"
           "kill -HUP $pid\n"
           "for i in $(seq 100); do list | grep -q '\"id\": \"second\"' && break; sleep 0.05; "
           "done\n"
           "list | grep -c '\"id\": \"second\"' | sed 's/^/after=/'\n"
           "kill -0 $pid && echo alive\n"
           "kill -TERM $pid\n"
           "wait $pid\n"
           "echo \"exit=$?\"\n"
           "cat $log\n";
  }
  const auto r = runCommand("timeout 60 bash " + script.string());
  EXPECT_NE(r.out.find("before=0"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("after=1"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("alive"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("exit=0"), std::string::npos) << r.out << r.err;
  EXPECT_NE(r.out.find("SIGHUP"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("added"), std::string::npos) << r.out;
  const auto help = runTinsmith("serve --help");
  EXPECT_NE(help.out.find("SIGHUP"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--workers"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--queue"), std::string::npos) << help.out;
}

}  // namespace
}  // namespace tinsmith::test
