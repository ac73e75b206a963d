// --on-demand: a store missing tiles its tileset references serves them,
// built from its TIN with the bytes the offline tiler wrote; many clients
// asking for one missing tile at once get it built once (the metrics count
// it); a built tile is kept (cache and store, readable by a fresh reader);
// tiles the tileset does not reference stay 404; without --on-demand a
// missing tile is a 404. And `tinsmith tile --store-until-zoom` writes such a
// store: the same tileset.json as a whole run, the deep tiles left out.
#include <gtest/gtest.h>

#include <atomic>
#include <nlohmann/json.hpp>

#include "core/tiles/tileset_json.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

/// The test store's tiles, key → bytes.
std::map<std::string, std::string> storedTiles() {
  const auto store = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  std::map<std::string, std::string> tiles;
  for (const auto& key : store->keys())
    if (key.starts_with("tiles/")) tiles[key] = store->get(key).value();
  return tiles;
}

int zoomOf(const std::string& key) {
  return std::stoi(key.substr(6));
}

bool aboveZoom2(const std::string& key) {
  return !key.starts_with("tiles/") || zoomOf(key) < 2;
}

server::TileServerOptions onDemandOptions(const std::filesystem::path& store) {
  auto o = RunningServer::defaults();
  o.stores = {store};
  o.service.onDemand = true;
  o.http.threads = 4;
  return o;
}

void expectMissingTilesBuiltAsOffline(const std::string& name) {
  const auto all = storedTiles();
  std::size_t deep = 0;
  for (const auto& [key, bytes] : all) deep += zoomOf(key) >= 2;
  ASSERT_GE(deep, 4u) << "the test store should reach zoom 2";
  const auto path = testStoreCopy("server-on-demand-" + name, name, aboveZoom2);
  const std::string id = std::filesystem::path(name).stem().string();
  {
    RunningServer server(onDemandOptions(path));
    HttpConnection c(server.port());
    for (const auto& [key, bytes] : all) {
      const auto r = c.request("/tilesets/" + id + "/" + key);
      ASSERT_EQ(r.status, 200) << key << ": " << r.body;
      EXPECT_EQ(r.header("content-type"), "model/gltf-binary");
      EXPECT_TRUE(r.body == bytes) << key << " differs from the offline tiler's";
    }
    EXPECT_EQ(server.server().metrics().tilesBuilt(), deep);
    // Kept: asked again, nothing more is built.
    for (const auto& [key, bytes] : all)
      if (zoomOf(key) >= 2) {
        EXPECT_EQ(c.request("/tilesets/" + id + "/" + key).status, 200);
      }
    EXPECT_EQ(server.server().metrics().tilesBuilt(), deep);
  }
  // The archive is back in a rollback journal: nothing beside it.
  EXPECT_FALSE(std::filesystem::exists(path.string() + "-wal"));
  // Written into the store: a fresh reader has every tile, byte for byte.
  const auto again = store::openStoreForReading(path);
  for (const auto& [key, bytes] : all) EXPECT_EQ(again->get(key), bytes) << key;
}

TEST(OnDemand, MissingTilesOfAnArchiveAreBuiltWithTheOfflineBytesAndKept) {
  expectMissingTilesBuiltAsOffline("lazy.3dtiles");
}

TEST(OnDemand, MissingTilesOfADirectoryStoreAreBuiltWithTheOfflineBytesAndKept) {
  expectMissingTilesBuiltAsOffline("lazy-dir");
}

TEST(OnDemand, TheServersOwnWritesDoNotReloadTheStore) {
  const auto path = testStoreCopy("server-on-demand-reload", "own.3dtiles", aboveZoom2);
  auto options = onDemandOptions(path);
  options.reloadInterval = std::chrono::milliseconds(20);
  RunningServer server(options);
  HttpConnection c(server.port());
  for (const auto& [key, bytes] : storedTiles()) {
    ASSERT_EQ(c.request("/tilesets/own/" + key).status, 200) << key;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(server.server().catalog().version(), 0u);  // never swapped
}

TEST(OnDemand, ManyClientsAskingForOneMissingTileGetItBuiltOnce) {
  const auto all = storedTiles();
  std::string key;
  for (const auto& [k, bytes] : all)
    if (zoomOf(k) >= 2) key = k;  // the last, deepest tile
  const auto path = testStoreCopy("server-on-demand-flight", "flight.3dtiles", aboveZoom2);
  RunningServer server(onDemandOptions(path));
  constexpr int kClients = 24;
  std::atomic<int> right{0};
  std::vector<std::thread> clients;
  for (int k = 0; k < kClients; ++k)
    clients.emplace_back([&] {
      const auto r = httpGet(server.port(), "/tilesets/flight/" + key);
      if (r.status == 200 && r.body == all.at(key)) ++right;
    });
  for (auto& t : clients) t.join();
  EXPECT_EQ(right.load(), kClients);
  EXPECT_EQ(server.server().metrics().tilesBuilt(), 1u);
  const std::string metrics = httpGet(server.port(), "/metrics").body;
  EXPECT_NE(metrics.find("tinsmith_tiles_built_on_demand_total 1\n"), std::string::npos) << metrics;
  // The build (the pyramid's plan and the zoom's fit: tenths of a second)
  // usually outlasts the clients' arrival, so some of them wait for it; but
  // on a loaded machine the scheduler may let every other client in only
  // after it, when the cache answers. Either way: one build, right bytes,
  // and no more waits than other clients.
  const std::string waits = "\ntinsmith_on_demand_waits_total ";
  const auto at = metrics.find(waits);
  ASSERT_NE(at, std::string::npos);
  const int waited = std::stoi(metrics.substr(at + waits.size()));
  EXPECT_LE(waited, kClients - 1) << metrics;
  RecordProperty("clients_that_waited_for_the_build", waited);
}

TEST(OnDemand, TilesTheTilesetDoesNotReferenceStay404) {
  const auto all = storedTiles();
  const auto path = testStoreCopy("server-on-demand-404", "holes.3dtiles", aboveZoom2);
  RunningServer server(onDemandOptions(path));
  // Beyond the pyramid's deepest zoom, and outside its grid.
  EXPECT_EQ(httpGet(server.port(), "/tilesets/holes/tiles/4/0/0.glb").status, 404);
  EXPECT_EQ(httpGet(server.port(), "/tilesets/holes/tiles/1/2/0.glb").status, 404);
  // Inside the grid, but under a tile that meets the tolerance (or holds no
  // terrain): the tileset never names it.
  int unreferenced = 0;
  for (int x = 0; x < 8 && unreferenced < 3; ++x)
    for (int y = 0; y < 8 && unreferenced < 3; ++y) {
      const std::string key =
          tiles::tileContentKey({3, static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)});
      if (all.contains(key)) continue;
      EXPECT_EQ(httpGet(server.port(), "/tilesets/holes/" + key).status, 404) << key;
      ++unreferenced;
    }
  EXPECT_EQ(server.server().metrics().tilesBuilt(), 0u);
}

TEST(OnDemand, WithoutTheOptionAMissingTileIs404) {
  const auto all = storedTiles();
  std::string key;
  for (const auto& [k, bytes] : all)
    if (zoomOf(k) >= 2) key = k;
  const auto path = testStoreCopy("server-on-demand-off", "off.3dtiles", aboveZoom2);
  auto options = onDemandOptions(path);
  options.service.onDemand = false;
  RunningServer server(options);
  EXPECT_EQ(httpGet(server.port(), "/tilesets/off/" + key).status, 404);
  EXPECT_EQ(server.server().metrics().tilesBuilt(), 0u);
}

TEST(OnDemand, AStoreOfAnOlderTinsmithBuildsNoTileThatWouldNotFitIt) {
  // Its build record's format says its tiles follow other rules (before
  // the current format, other quantization and chord sag): a tile
  // built now would not share its sides with the stored ones bit for bit.
  const auto all = storedTiles();
  std::string deep, top;
  for (const auto& [k, bytes] : all) (zoomOf(k) >= 2 ? deep : top) = k;
  const auto path = testStoreCopy("server-on-demand-older", "older.3dtiles", aboveZoom2);
  {
    auto st = store::openStoreForWriting(path, true);
    std::string build = st->get("tinsmith/build.json").value();
    const std::string now = ingest::kTileBuildFormat;
    const auto at = build.find(now);
    ASSERT_NE(at, std::string::npos) << build;
    build.replace(at, now.size(), "tinsmith-tiles/1");
    st->put("tinsmith/build.json", build);
  }
  RunningServer server(onDemandOptions(path));
  const auto r = httpGet(server.port(), "/tilesets/older/" + deep);
  EXPECT_GE(r.status, 500) << r.body;
  EXPECT_EQ(server.server().metrics().tilesBuilt(), 0u);
  EXPECT_FALSE(store::openStoreForReading(path)->contains(deep));
  EXPECT_EQ(httpGet(server.port(), "/tilesets/older/" + top).status, 200);  // the stored ones
}

TEST(OnDemand, TileStoreUntilZoomWritesTheWholeTilesetAndOnlyTheTilesAbove) {
  const auto dir = scratchDir("server-store-until-" + std::to_string(::getpid()));
  const auto lazy = dir / "lazy.3dtiles";
  const auto r =
      runTinsmith("tile -q " + (testStoreDir() / "hill.tin").string() + " -o " + lazy.string() +
                  " --tolerance 0.25 --max-triangles 512 --max-zoom 3 "
                  "--store-until-zoom 2");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto full = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
  const auto part = store::openStoreForReading(lazy);
  for (const auto& key : full->keys()) {
    if (key.starts_with("tiles/") && zoomOf(key) >= 2) {
      EXPECT_FALSE(part->contains(key)) << key;
    } else {
      EXPECT_EQ(part->get(key), full->get(key)) << key;  // tileset.json, build record, TIN
    }
  }
  // Served with --on-demand, it is the whole store.
  RunningServer server(onDemandOptions(lazy));
  HttpConnection c(server.port());
  for (const auto& key : full->keys())
    if (key.starts_with("tiles/")) {
      EXPECT_TRUE(c.request("/tilesets/lazy/" + key).body == full->get(key)) << key;
    }
  // A shard cannot leave tiles out.
  const auto bad =
      runTinsmith("tile -q " + (testStoreDir() / "hill.tin").string() + " -o " +
                  (dir / "x.3dtiles").string() + " --until-zoom 2 --store-until-zoom 1");
  EXPECT_EQ(bad.exitCode, 2) << bad.err;
  EXPECT_NE(bad.err.find("--store-until-zoom is for a whole pyramid"), std::string::npos)
      << bad.err;
}

}  // namespace
}  // namespace tinsmith::test
