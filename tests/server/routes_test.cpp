// Every route of a running server over real HTTP: statuses, headers, ETag and
// 304, HEAD, ranges, CORS, gzip, JSON errors, and elevations that agree with
// `tinsmith query` on the same TIN.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "ingest/store/tile_store.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

using nlohmann::json;

class Routes : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    store_ = store::openStoreForReading(testStoreDir() / "hill.3dtiles");
    server_ = new RunningServer();
  }
  static void TearDownTestSuite() {
    delete server_;
    store_.reset();
  }
  static unsigned short port() { return server_->port(); }
  static std::vector<std::string> tileKeys() {
    std::vector<std::string> keys;
    for (const auto& k : store_->keys())
      if (k.starts_with("tiles/")) keys.push_back(k);
    return keys;
  }
  static std::string stored(const std::string& key) { return store_->get(key).value(); }

  static inline std::unique_ptr<store::TileStore> store_;
  static inline RunningServer* server_ = nullptr;
};

void expectJsonError(const HttpResponse& r, int status, const std::string& parameter = "") {
  EXPECT_EQ(r.status, status);
  EXPECT_EQ(r.header("content-type"), "application/json");
  const auto body = json::parse(r.body, nullptr, false);
  ASSERT_TRUE(body.is_object()) << r.body;
  EXPECT_EQ(body["error"]["status"], status) << r.body;
  EXPECT_FALSE(body["error"]["message"].get<std::string>().empty());
  if (!parameter.empty()) {
    EXPECT_EQ(body["error"]["parameter"], parameter) << r.body;
  }
}

TEST_F(Routes, TilesetsListDescribesTheStore) {
  const auto r = httpGet(port(), "/tilesets");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.header("content-type"), "application/json");
  const auto list = json::parse(r.body);
  ASSERT_EQ(list["tilesets"].size(), 1u);
  const auto& t = list["tilesets"][0];
  EXPECT_EQ(t["id"], "hill");
  EXPECT_EQ(t["crs"], "EPSG:26912");
  EXPECT_EQ(t["tileCount"], tileKeys().size());
  EXPECT_GE(tileKeys().size(), 5u);
  EXPECT_EQ(t["tolerance"], 0.25);
  EXPECT_EQ(t["zooms"]["min"], 0);
  EXPECT_EQ(t["bounds"]["project"].size(), 4u);
  const auto& ll = t["bounds"]["lonlat"];
  ASSERT_EQ(ll.size(), 4u);
  EXPECT_LT(ll[0].get<double>(), -111.0);  // UTM 12N, west of -111°
  EXPECT_GT(ll[1].get<double>(), 40.0);
  EXPECT_EQ(t["elevation"], true);
}

TEST_F(Routes, EveryTileComesBackByteForByteWithItsHeaders) {
  HttpConnection c(port());
  for (const auto& key : tileKeys()) {
    const auto r = c.request("/tilesets/hill/" + key);  // one keep-alive connection
    ASSERT_EQ(r.status, 200) << key;
    EXPECT_EQ(r.body, stored(key)) << key;
    EXPECT_EQ(r.header("content-type"), "model/gltf-binary");
    EXPECT_EQ(r.header("cache-control"), "public, max-age=86400");
    EXPECT_EQ(r.header("accept-ranges"), "bytes");
    EXPECT_EQ(r.header("access-control-allow-origin"), "*");
    EXPECT_EQ(r.header("connection"), "keep-alive");
    EXPECT_EQ(r.header("etag").front(), '"');
  }
  const auto ts = c.request("/tilesets/hill/tileset.json");
  ASSERT_EQ(ts.status, 200);
  EXPECT_EQ(ts.body, stored("tileset.json"));
  EXPECT_EQ(ts.header("content-type"), "application/json");
  EXPECT_EQ(ts.header("cache-control"), "public, max-age=60, must-revalidate");
}

TEST_F(Routes, IfNoneMatchGives304AndOtherTagsTheBody) {
  const std::string target = "/tilesets/hill/" + tileKeys().front();
  HttpConnection c(port());
  const auto first = c.request(target);
  ASSERT_EQ(first.status, 200);
  const std::string etag = first.header("etag");
  const auto again = c.request(target, "If-None-Match: " + etag + "\r\n");
  EXPECT_EQ(again.status, 304);
  EXPECT_TRUE(again.body.empty());
  EXPECT_EQ(again.header("etag"), etag);
  EXPECT_EQ(c.request(target, "If-None-Match: \"other\", W/" + etag + "\r\n").status, 304);
  const auto changed = c.request(target, "If-None-Match: \"other\"\r\n");
  EXPECT_EQ(changed.status, 200);
  EXPECT_EQ(changed.body, first.body);
  // Another tile has another tag.
  EXPECT_NE(c.request("/tilesets/hill/" + tileKeys().back()).header("etag"), etag);
}

TEST_F(Routes, HeadSendsTheHeadersOnlyAndKeepsTheConnection) {
  const std::string key = tileKeys().front();
  HttpConnection c(port());
  const auto head = c.request("/tilesets/hill/" + key, "", "HEAD");
  ASSERT_EQ(head.status, 200);
  EXPECT_EQ(head.header("content-length"), std::to_string(stored(key).size()));
  EXPECT_TRUE(head.body.empty());
  const auto get = c.request("/tilesets/hill/" + key);  // the next response is not skewed
  EXPECT_EQ(get.status, 200);
  EXPECT_EQ(get.body, stored(key));
  EXPECT_EQ(get.header("etag"), head.header("etag"));
}

TEST_F(Routes, RangesGive206OrA416) {
  const std::string key = tileKeys().front();
  const std::string bytes = stored(key);
  const std::string target = "/tilesets/hill/" + key;
  HttpConnection c(port());
  auto r = c.request(target, "Range: bytes=0-99\r\n");
  ASSERT_EQ(r.status, 206);
  EXPECT_EQ(r.body, bytes.substr(0, 100));
  EXPECT_EQ(r.header("content-range"), "bytes 0-99/" + std::to_string(bytes.size()));
  r = c.request(target, "Range: bytes=-16\r\n");
  ASSERT_EQ(r.status, 206);
  EXPECT_EQ(r.body, bytes.substr(bytes.size() - 16));
  r = c.request(target, "Range: bytes=100-\r\n");
  EXPECT_EQ(r.body, bytes.substr(100));
  r = c.request(target, "Range: bytes=" + std::to_string(bytes.size()) + "-\r\n");
  expectJsonError(r, 416, "Range");
  EXPECT_EQ(r.header("content-range"), "bytes */" + std::to_string(bytes.size()));
  r = c.request(target, "Range: bytes=0-1,5-6\r\n");  // several ranges: the whole
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, bytes);
  r = c.request(target, "Range: bytes=0-9\r\nIf-Range: \"stale\"\r\n");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, bytes);
}

TEST_F(Routes, JsonIsGzippedWhenAcceptedWithItsOwnEtag) {
  HttpConnection c(port());
  const auto plain = c.request("/tilesets/hill/tileset.json");
  const auto packed =
      c.request("/tilesets/hill/tileset.json", "Accept-Encoding: deflate, gzip\r\n");
  ASSERT_EQ(packed.status, 200);
  EXPECT_EQ(packed.header("content-encoding"), "gzip");
  EXPECT_EQ(packed.header("vary"), "Accept-Encoding");
  EXPECT_EQ(plain.header("content-encoding"), "");
  EXPECT_LT(packed.body.size(), plain.body.size());
  EXPECT_EQ(gunzip(packed.body), stored("tileset.json"));
  EXPECT_NE(packed.header("etag"), plain.header("etag"));
  EXPECT_EQ(c.request("/tilesets/hill/tileset.json",
                      "Accept-Encoding: gzip\r\nIf-None-Match: " + packed.header("etag") + "\r\n")
                .status,
            304);
  EXPECT_EQ(c.request("/tilesets/hill/tileset.json", "Accept-Encoding: gzip;q=0\r\n")
                .header("content-encoding"),
            "");
  // Tiles are never gzipped (Draco is compressed already).
  EXPECT_EQ(c.request("/tilesets/hill/" + tileKeys().front(), "Accept-Encoding: gzip\r\n")
                .header("content-encoding"),
            "");
}

TEST_F(Routes, JsonIsBrotliWhenAcceptedBeforeGzipWithItsOwnEtag) {
  HttpConnection c(port());
  const auto plain = c.request("/tilesets/hill/tileset.json");
  const auto gz = c.request("/tilesets/hill/tileset.json", "Accept-Encoding: gzip\r\n");
  const auto br =
      c.request("/tilesets/hill/tileset.json", "Accept-Encoding: gzip, deflate, br\r\n");
  ASSERT_EQ(br.status, 200);
  EXPECT_EQ(br.header("content-encoding"), "br");
  EXPECT_EQ(br.header("vary"), "Accept-Encoding");
  EXPECT_EQ(unbrotli(br.body), stored("tileset.json"));
  EXPECT_LT(br.body.size(), gz.body.size());
  // Three representations, three tags; each revalidates as itself.
  EXPECT_NE(br.header("etag"), gz.header("etag"));
  EXPECT_NE(br.header("etag"), plain.header("etag"));
  EXPECT_EQ(c.request("/tilesets/hill/tileset.json",
                      "Accept-Encoding: br\r\nIf-None-Match: " + br.header("etag") + "\r\n")
                .status,
            304);
  // br refused: gzip; the tile stays as stored.
  EXPECT_EQ(c.request("/tilesets/hill/tileset.json", "Accept-Encoding: br;q=0, gzip\r\n")
                .header("content-encoding"),
            "gzip");
  EXPECT_EQ(c.request("/tilesets/hill/" + tileKeys().front(), "Accept-Encoding: br\r\n")
                .header("content-encoding"),
            "");
  // Made once: the cached tileset is compressed when it is read, not per request.
  const auto again = c.request("/tilesets/hill/tileset.json", "Accept-Encoding: br\r\n");
  EXPECT_EQ(again.body, br.body);
  // A JSON answer made per request (a batch of elevations) is compressed too.
  std::string points = "{\"points\": [";
  for (int i = 0; i < 200; ++i)
    points += (i ? "," : "") + std::string("[") + std::to_string(430100 + i) + ", 4515600]";
  points += "]}";
  const auto batch =
      c.request("/tilesets/hill/elevation",
                "Accept-Encoding: br\r\nContent-Type: application/json\r\n", "POST", points);
  ASSERT_EQ(batch.status, 200) << batch.body;
  EXPECT_EQ(batch.header("content-encoding"), "br");
  EXPECT_EQ(nlohmann::json::parse(unbrotli(batch.body))["points"].size(), 200u);
}

TEST_F(Routes, ErrorsAreJsonWithTheRightStatus) {
  HttpConnection c(port());
  expectJsonError(c.request("/tilesets/nope/tileset.json"), 404);
  expectJsonError(c.request("/tilesets/nope/tiles/0/0/0.glb"), 404);
  expectJsonError(c.request("/nothing/here"), 404);
  expectJsonError(c.request("/tilesets/hill/tiles/0/1/0.glb"), 404);    // x ≥ 2^z
  expectJsonError(c.request("/tilesets/hill/tiles/25/0/0.glb"), 404);   // below the pyramid
  expectJsonError(c.request("/tilesets/hill/tilesets/9/9/9.json"), 404);
  expectJsonError(c.request("/tilesets/hill/tiles/x/0/0.glb"), 400, "z");
  expectJsonError(c.request("/tilesets/hill/tiles/1/-1/0.glb"), 400, "x");
  expectJsonError(c.request("/tilesets/hill/tiles/1/0/0.jpg"), 400, "y");
  expectJsonError(c.request("/tilesets/hill/elevation?x=1"), 400, "y");
  expectJsonError(c.request("/tilesets/hill/elevation?x=1e999&y=2"), 400, "x");
  expectJsonError(c.request("/tilesets/hill/elevation"), 400, "x");
  expectJsonError(c.request("/tilesets/hill/elevation?lon=200&lat=40"), 400, "lon");
  expectJsonError(c.request("/tilesets/hill/elevation?x=1&y=2&lon=1&lat=2"), 400, "lon");
  expectJsonError(c.request("/tilesets/hill/elevation?x=0&y=0"), 404);  // off the TIN
  expectJsonError(c.request("/tilesets/hill/profile?line=1,2"), 400, "line");
  expectJsonError(c.request("/tilesets/hill/profile?line=430000,4515000;431000,4515000&spacing=0.001"),
                  400, "spacing");
  expectJsonError(c.request("/tilesets/hill/elevation", "", "POST", "not json"), 400, "body");
  expectJsonError(c.request("/tilesets/hill/elevation", "", "POST", R"({"points": [[1]]})"), 400,
                  "points[0]");
  auto r = c.request("/tilesets/hill/tileset.json", "", "DELETE");
  expectJsonError(r, 405);
  EXPECT_EQ(r.header("allow"), "GET, HEAD, OPTIONS");
  r = c.request("/tilesets", "", "POST", "{}");
  expectJsonError(r, 405);
  r = c.request("/tilesets/hill/elevation", "", "PUT", "{}");
  EXPECT_EQ(r.header("allow"), "GET, HEAD, POST, OPTIONS");
  // The connection survived every error.
  EXPECT_EQ(c.request("/health").status, 200);
}

TEST_F(Routes, IndexHealthAndMetrics) {
  auto r = httpGet(port(), "/");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.header("content-type"), "text/html; charset=utf-8");
  EXPECT_NE(r.body.find("/tilesets/hill/tileset.json"), std::string::npos);
  r = httpGet(port(), "/health");
  EXPECT_EQ(json::parse(r.body)["status"], "ok");
  r = httpGet(port(), "/metrics");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.header("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_NE(r.body.find("tinsmith_http_requests_total{route=\"index\",status=\"200\"}"),
            std::string::npos);
  EXPECT_NE(r.body.find("tinsmith_http_request_duration_seconds_bucket{le=\"+Inf\"}"),
            std::string::npos);
  EXPECT_NE(r.body.find("tinsmith_open_connections "), std::string::npos);
}

TEST(RoutesCors, OriginIsConfigurableOrOffAndPreflightAnswers) {
  auto options = RunningServer::defaults();
  options.service.cors = "https://maps.example.org";
  RunningServer one(options);
  auto r = httpGet(one.port(), "/tilesets");
  EXPECT_EQ(r.header("access-control-allow-origin"), "https://maps.example.org");
  EXPECT_EQ(r.header("vary"), "Origin");
  HttpConnection c(one.port());
  r = c.request("/tilesets/hill/elevation", "Origin: https://maps.example.org\r\n"
                "Access-Control-Request-Method: POST\r\n", "OPTIONS");
  EXPECT_EQ(r.status, 204);
  EXPECT_EQ(r.header("access-control-allow-methods"), "GET, HEAD, POST, OPTIONS");
  EXPECT_NE(r.header("access-control-allow-headers").find("Range"), std::string::npos);

  options.service.cors = "";
  RunningServer off(options);
  r = httpGet(off.port(), "/tilesets");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.header("access-control-allow-origin"), "");
}

double queryZ(double x, double y) {
  char args[128];
  std::snprintf(args, sizeof args, " %.17g %.17g --json", x, y);
  const auto r = runTinsmith("query " + (testStoreDir() / "hill.tin").string() + args);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return json::parse(r.out)["z"].get<double>();
}

TEST_F(Routes, ElevationsAgreeWithTinsmithQuery) {
  HttpConnection c(port());
  const std::vector<std::pair<double, double>> points{
      {430100.5, 4515100.25}, {430617.125, 4515700.0}, {431100.0, 4516150.75}, {430000.0, 4515000.0}};
  json batch = {{"points", json::array()}};
  for (const auto& [x, y] : points) {
    char target[160];
    std::snprintf(target, sizeof target, "/tilesets/hill/elevation?x=%.17g&y=%.17g", x, y);
    const auto r = c.request(target);
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(json::parse(r.body)["z"].get<double>(), queryZ(x, y)) << x << " " << y;
    batch["points"].push_back({x, y});
  }
  batch["points"].push_back({1.0, 2.0});  // off the TIN: null in a batch
  const auto r = c.request("/tilesets/hill/elevation", "Content-Type: application/json\r\n", "POST",
                           batch.dump());
  ASSERT_EQ(r.status, 200) << r.body;
  const auto answer = json::parse(r.body);
  ASSERT_EQ(answer["points"].size(), points.size() + 1);
  for (std::size_t i = 0; i < points.size(); ++i)
    EXPECT_EQ(answer["points"][i]["z"].get<double>(), queryZ(points[i].first, points[i].second));
  EXPECT_TRUE(answer["points"].back()["z"].is_null());

  // lon/lat: converted through PROJ into the project CRS, then the same z.
  // The middle of the tileset's lon/lat bounds lies on the TIN.
  const auto bounds = json::parse(c.request("/tilesets").body)["tilesets"][0]["bounds"]["lonlat"];
  const double lon = (bounds[0].get<double>() + bounds[2].get<double>()) / 2;
  const double lat = (bounds[1].get<double>() + bounds[3].get<double>()) / 2;
  char target[160];
  std::snprintf(target, sizeof target, "/tilesets/hill/elevation?lon=%.17g&lat=%.17g", lon, lat);
  const auto ll = json::parse(c.request(target).body);
  ASSERT_TRUE(ll["z"].is_number()) << ll.dump();
  EXPECT_EQ(ll["z"].get<double>(), queryZ(ll["x"].get<double>(), ll["y"].get<double>()));
  EXPECT_NEAR(ll["x"].get<double>(), 430600, 100);  // near the 1.2 km square's middle
  EXPECT_NEAR(ll["y"].get<double>(), 4515600, 100);
}

TEST_F(Routes, ABodyBehindExpect100ContinueIsAskedFor) {
  HttpConnection c(port());
  const std::string body = R"({"points": [[430100.5, 4515100.25]]})";
  ASSERT_TRUE(c.send("POST /tilesets/hill/elevation HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\n"
                     "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n"));
  EXPECT_EQ(c.read().status, 100);  // sent before the body
  ASSERT_TRUE(c.send(body));
  const auto r = c.read();
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(json::parse(r.body)["points"][0]["z"].get<double>(), queryZ(430100.5, 4515100.25));
}

TEST_F(Routes, ProfilesSampleTheLineAtTheSpacing) {
  const auto r = httpGet(port(), "/tilesets/hill/profile?line=430100,4515100;430900,4515100;430900,4515700&spacing=100");
  ASSERT_EQ(r.status, 200) << r.body;
  const auto p = json::parse(r.body);
  EXPECT_DOUBLE_EQ(p["length"].get<double>(), 1400.0);
  const auto& s = p["samples"];
  ASSERT_EQ(s.size(), 15u);  // 0, 100, …, 1400, the corner at 800 once
  double previous = -1;
  for (const auto& sample : s) {
    EXPECT_GT(sample["distance"].get<double>(), previous);
    previous = sample["distance"].get<double>();
    const auto e = json::parse(httpGet(port(), "/tilesets/hill/elevation?x=" + sample["x"].dump() +
                                                   "&y=" + sample["y"].dump())
                                   .body);
    EXPECT_EQ(sample["z"], e["z"]);
  }
  EXPECT_EQ(s.back()["distance"].get<double>(), 1400.0);
  const auto post = httpGet(port(), "/tilesets/hill/profile?line=430100,4515100;430900,4515100;430900,4515700&spacing=100");
  EXPECT_EQ(post.body, r.body);
  HttpConnection c(port());
  const auto viaPost = c.request("/tilesets/hill/profile", "", "POST",
                                 R"({"line": [[430100,4515100],[430900,4515100],[430900,4515700]], "spacing": 100})");
  ASSERT_EQ(viaPost.status, 200) << viaPost.body;
  EXPECT_EQ(json::parse(viaPost.body)["samples"], s);
}

}  // namespace
}  // namespace tinsmith::test
