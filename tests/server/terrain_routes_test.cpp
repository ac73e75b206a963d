// Cesium terrain over real HTTP, at the URLs CesiumJS's CesiumTerrainProvider
// asks for: layer.json, then {z}/{x}/{y}.terrain with
//   Accept: application/vnd.quantized-mesh;extensions=octvertexnormals-watermask-metadata,…
// — a tile carries exactly the extensions asked for (none without the
// parameter, as Cesium's own servers answer), gzip when accepted, an ETag
// per representation, Vary: Accept, CORS; 404 for a tile the store lacks, one
// outside the grid and a tileset with no terrain. The store holds both
// schemes (tinsmith tile --scheme both), as the demo's does.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/encode/quantized_mesh.hpp"
#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"
#include "tests/support/quantized_mesh_decoder.hpp"

namespace tinsmith::test {
namespace {

using nlohmann::json;

/// "hill-both.3dtiles": the test TIN tiled as 3D Tiles and Cesium terrain.
std::filesystem::path bothSchemesStore() {
  static const std::filesystem::path path = [] {
    const auto p = testStoreDir() / "hill-both.3dtiles";
    ingest::TileJobOptions options;
    options.tiler.tolerance = 2;
    options.tiler.maxTriangles = 512;
    options.tiler.maxZoom = 2;
    options.scheme = ingest::TileScheme::Both;
    ingest::runTileJob(testTin(), (testStoreDir() / "hill.tin").string(), p, options);
    return p;
  }();
  return path;
}

class TerrainRoutes : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    store_ = store::openStoreForReading(bothSchemesStore());
    auto options = RunningServer::defaults();
    options.stores = {bothSchemesStore(), testStoreDir() / "hill.3dtiles"};
    server_ = new RunningServer(options);
  }
  static void TearDownTestSuite() {
    delete server_;
    store_.reset();
  }
  static unsigned short port() { return server_->port(); }
  static std::vector<std::string> terrainKeys() {
    std::vector<std::string> keys;
    for (const auto& k : store_->keys())
      if (k.starts_with("terrain/") && k.ends_with(".terrain")) keys.push_back(k);
    return keys;
  }
  static std::string stored(const std::string& key) { return store_->get(key).value(); }

  static inline std::unique_ptr<store::TileStore> store_;
  static inline RunningServer* server_ = nullptr;
};

constexpr const char* kCesiumAccept =
    "Accept: application/vnd.quantized-mesh;extensions=octvertexnormals-watermask-metadata,"
    "application/octet-stream;q=0.9,*/*;q=0.01\r\n";

std::vector<int> extensionIds(const std::string& bytes) {
  const auto d = decodeQuantizedMesh(bytes);
  EXPECT_TRUE(d.ok);
  std::vector<int> ids;
  for (const auto& [id, payload] : d.extensions) ids.push_back(id);
  return ids;
}

TEST_F(TerrainRoutes, TheListLinksTheLayerAndTheLayerIsServedAsStored) {
  const auto list = json::parse(httpGet(port(), "/tilesets").body);
  ASSERT_EQ(list["tilesets"].size(), 2u);
  for (const auto& t : list["tilesets"]) {
    if (t["id"] == "hill-both") {
      EXPECT_EQ(t["links"]["terrain"], "/tilesets/hill-both/terrain/layer.json");
    } else {
      EXPECT_FALSE(t["links"].contains("terrain")) << t.dump();
    }
  }
  const auto r = httpGet(port(), "/tilesets/hill-both/terrain/layer.json");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.body, stored("terrain/layer.json"));
  EXPECT_EQ(r.header("content-type"), "application/json");
  EXPECT_EQ(r.header("access-control-allow-origin"), "*");
  const auto layer = json::parse(r.body);
  EXPECT_EQ(layer["format"], "quantized-mesh-1.0");
  EXPECT_EQ(layer["tiles"][0], "{z}/{x}/{y}.terrain");
}

TEST_F(TerrainRoutes, EveryTileCarriesTheExtensionsAskedForAndNoOthers) {
  const auto keys = terrainKeys();
  ASSERT_GE(keys.size(), 3u);
  HttpConnection c(port());
  for (const auto& key : keys) {
    const std::string target = "/tilesets/hill-both/" + key;
    // CesiumJS's request: all three, in the store's bytes exactly.
    const auto all = c.request(target, kCesiumAccept);
    ASSERT_EQ(all.status, 200) << key;
    EXPECT_EQ(all.body, stored(key)) << key;
    EXPECT_EQ(all.header("content-type"), "application/vnd.quantized-mesh");
    EXPECT_EQ(all.header("vary"), "Accept");
    EXPECT_EQ(all.header("access-control-allow-origin"), "*");
    EXPECT_EQ((extensionIds(all.body)), (std::vector<int>{1, 2, 4})) << key;
    // 3d-tiles-renderer's QuantizedMeshPlugin puts the parameter on the
    // octet-stream range.
    const auto three =
        c.request(target,
                  "Accept: application/vnd.quantized-mesh,application/octet-stream;q=0.9;"
                  "extensions=octvertexnormals-watermask-metadata\r\n");
    EXPECT_EQ(three.body, stored(key)) << key;
    // No parameter: the mesh alone, which still decodes.
    const auto plain = c.request(target);
    ASSERT_EQ(plain.status, 200) << key;
    EXPECT_TRUE(extensionIds(plain.body).empty()) << key;
    EXPECT_NE(plain.header("etag"), all.header("etag")) << key;
    // Normals alone, named in another case.
    const auto normals =
        c.request(target, "Accept: application/vnd.quantized-mesh;extensions=OctVertexNormals\r\n");
    EXPECT_EQ((extensionIds(normals.body)), (std::vector<int>{1})) << key;
    EXPECT_EQ(decodeQuantizedMesh(normals.body).u, decodeQuantizedMesh(all.body).u) << key;
  }
}

TEST_F(TerrainRoutes, TilesAreGzippedWhenAcceptedAndAnswer304ToTheirTag) {
  const std::string target = "/tilesets/hill-both/" + terrainKeys().front();
  HttpConnection c(port());
  const auto packed =
      c.request(target, std::string(kCesiumAccept) + "Accept-Encoding: gzip, deflate, br\r\n");
  ASSERT_EQ(packed.status, 200);
  const std::string encoding = packed.header("content-encoding");
  ASSERT_TRUE(encoding == "gzip" || encoding == "br") << encoding;
  const std::string body = encoding == "gzip" ? gunzip(packed.body) : unbrotli(packed.body);
  EXPECT_EQ(body, stored(terrainKeys().front()));
  EXPECT_LT(packed.body.size(), body.size());
  const auto again =
      c.request(target, std::string(kCesiumAccept) + "Accept-Encoding: gzip, deflate, br\r\n" +
                            "If-None-Match: " + packed.header("etag") + "\r\n");
  EXPECT_EQ(again.status, 304);
}

TEST_F(TerrainRoutes, MissingTilesOffGridTilesAndTilesetsWithoutTerrainAre404) {
  // Level 0 has two columns: x = 1 is a tile, x = 2 is not.
  EXPECT_EQ(httpGet(port(), "/tilesets/hill-both/terrain/0/1/0.terrain").status, 200);
  const auto off = httpGet(port(), "/tilesets/hill-both/terrain/0/2/0.terrain");
  EXPECT_EQ(off.status, 404);
  EXPECT_NE(off.body.find("outside the geographic grid"), std::string::npos) << off.body;
  // A tile of the grid the layer does not list (level 3 over the Pacific).
  const auto missing = httpGet(port(), "/tilesets/hill-both/terrain/3/0/0.terrain");
  EXPECT_EQ(missing.status, 404);
  EXPECT_NE(missing.body.find("layer.json lists"), std::string::npos) << missing.body;
  const auto none = httpGet(port(), "/tilesets/hill/terrain/layer.json");
  EXPECT_EQ(none.status, 404);
  EXPECT_NE(none.body.find("--scheme both"), std::string::npos) << none.body;
  EXPECT_EQ(httpGet(port(), "/tilesets/hill-both/terrain/0/0/x.terrain").status, 400);
}

TEST(TerrainRoutesDamaged, ADamagedStoredTileIsTheServers500NotTheClients400) {
  const auto source = store::openStoreForReading(bothSchemesStore());
  const auto dir = scratchDir("terrain-damaged-" + std::to_string(::getpid())) / "hill-both";
  store::writeStore(*source, source->keys(), dir);
  const std::string key = "terrain/0/0/0.terrain";
  std::ofstream(dir / key, std::ios::binary | std::ios::trunc)
      << source->get(key).value().substr(0, 300);
  auto options = RunningServer::defaults();
  options.stores = {dir};
  RunningServer server(options);
  const auto r = httpGet(server.port(), "/tilesets/hill-both/" + key);
  EXPECT_EQ(r.status, 500) << r.body;
  EXPECT_EQ(httpGet(server.port(), "/tilesets/hill-both/terrain/0/1/0.terrain").status, 200);
}

}  // namespace
}  // namespace tinsmith::test
