// A store replaced on disk while it is served (a new archive renamed over
// the old one, as `tinsmith tile` writes it) is picked up whole: every
// response is entirely the old store's or entirely the new one's, and after
// the swap the new one's bytes, listing and tile count are served.
#include <gtest/gtest.h>

#include <atomic>

#include <nlohmann/json.hpp>

#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

TEST(Reload, AStoreRenamedOverIsServedWholeNeverTorn) {
  namespace fs = std::filesystem;
  const auto dir = scratchDir("server-reload-" + std::to_string(::getpid()));
  const auto live = dir / "live.3dtiles";
  fs::copy_file(testStoreDir() / "hill.3dtiles", live);
  const auto oldStore = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  const auto newStore = store::openStoreForReading(coarseStore());
  const std::string oldTileset = oldStore->get("tileset.json").value();
  const std::string newTileset = newStore->get("tileset.json").value();
  const std::string oldTile = oldStore->get("tiles/0/0/0.glb").value();
  const std::string newTile = newStore->get("tiles/0/0/0.glb").value();
  ASSERT_NE(oldTileset, newTileset);
  ASSERT_NE(oldTile, newTile);

  auto options = RunningServer::defaults();
  options.stores = {live};
  options.reloadInterval = std::chrono::milliseconds(50);
  RunningServer server(options);

  std::atomic<bool> stop{false};
  std::atomic<int> torn{0}, fetched{0};
  std::thread reader([&] {
    HttpConnection c(server.port());
    while (!stop) {
      const auto t = c.request("/tilesets/live/tileset.json");
      const auto g = c.request("/tilesets/live/tiles/0/0/0.glb");
      ++fetched;
      if (t.body != oldTileset && t.body != newTileset) ++torn;
      if (g.body != oldTile && g.body != newTile) ++torn;
    }
  });
  while (fetched < 5) std::this_thread::yield();

  fs::copy_file(coarseStore(), dir / "live.new.3dtiles");
  fs::rename(dir / "live.new.3dtiles", live);
  bool swapped = false;
  for (int i = 0; i < 2000 && !swapped; ++i) {  // at most 20 s
    swapped = httpGet(server.port(), "/tilesets/live/tileset.json").body == newTileset;
    if (!swapped) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const int before = fetched;
  while (fetched < before + 5) std::this_thread::yield();  // the reader sees the swap too
  stop = true;
  reader.join();
  EXPECT_TRUE(swapped);
  EXPECT_EQ(torn.load(), 0);
  EXPECT_EQ(httpGet(server.port(), "/tilesets/live/tiles/0/0/0.glb").body, newTile);
  std::size_t newTiles = 0;
  for (const auto& key : newStore->keys()) newTiles += key.starts_with("tiles/");
  const auto list = nlohmann::json::parse(httpGet(server.port(), "/tilesets").body);
  EXPECT_EQ(list["tilesets"][0]["tileCount"], newTiles);
}

TEST(Reload, AStoreAddedToAServedFolderIsServed) {
  namespace fs = std::filesystem;
  const auto dir = scratchDir("server-folder-" + std::to_string(::getpid()));
  fs::create_directories(dir / "stores");
  auto options = RunningServer::defaults();
  options.stores = {dir / "stores"};  // empty at the start, as in the Docker image
  options.reloadInterval = std::chrono::milliseconds(50);
  RunningServer server(options);
  EXPECT_EQ(nlohmann::json::parse(httpGet(server.port(), "/tilesets").body)["tilesets"].size(), 0u);
  EXPECT_EQ(httpGet(server.port(), "/tilesets/late/tileset.json").status, 404);

  fs::copy_file(testStoreDir() / "hill.3dtiles", dir / "late.copying");
  fs::rename(dir / "late.copying", dir / "stores/late.3dtiles");
  HttpResponse r;
  for (int i = 0; i < 2000 && r.status != 200; ++i) {  // at most 20 s
    r = httpGet(server.port(), "/tilesets/late/tileset.json");
    if (r.status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body,
            store::openStoreForReading(testStoreDir() / "hill.3dtiles")->get("tileset.json").value());
  const auto list = nlohmann::json::parse(httpGet(server.port(), "/tilesets").body);
  ASSERT_EQ(list["tilesets"].size(), 1u);
  EXPECT_EQ(list["tilesets"][0]["id"], "late");
}

}  // namespace
}  // namespace tinsmith::test
