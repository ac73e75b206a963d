// The viewer's routes on a running server: slope and aspect in the
// elevation answer against a hand computation on a tilted plane, the break
// lines as GeoJSON (lines.geojson), the viewer's files from the start-up
// table (types, caching, nothing outside it), the page without a viewer, and
// every route under --base-path.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "server/app/tile_service.hpp"
#include "tests/server/server_test_support.hpp"

namespace tinsmith::test {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr double kX0 = 430000, kY0 = 4515000;
/// The plane every vertex of the test TIN lies on: ∂z/∂x = 0.1, ∂z/∂y = 0.2.
double planeZ(double x, double y) {
  return 1000 + 0.1 * (x - kX0) + 0.2 * (y - kY0);
}

/// A 600 m square on the plane with a road (3 vertices) and a river
/// (4 vertices) as constraints, tiled into "plane.3dtiles" (no geoid, so
/// heights above the ellipsoid are the TIN's z); built once.
fs::path planeStore() {
  static const fs::path path = [] {
    const auto dir = scratchDir("viewer-store-" + std::to_string(::getpid()));
    Cdt cdt;
    const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "grid");
    const FeatureId road = cdt.addFeature(FeatureKind::Road, "road.geojson, feature 0");
    const FeatureId river = cdt.addFeature(FeatureKind::River, "streams.geojson, feature 0");
    std::vector<Point3> points;
    for (int j = 0; j <= 12; ++j)
      for (int i = 0; i <= 12; ++i)
        points.push_back({kX0 + i * 50.0, kY0 + j * 50.0, planeZ(kX0 + i * 50.0, kY0 + j * 50.0)});
    cdt.insertPoints(points, spots);
    const auto on = [](double x, double y) {
      return Point3{kX0 + x, kY0 + y, planeZ(kX0 + x, kY0 + y)};
    };
    const std::vector<Point3> roadLine{on(60, 110), on(300, 140), on(540, 130)};
    const std::vector<Point3> riverLine{on(110, 520), on(230, 410), on(330, 330), on(480, 260)};
    cdt.insertConstraint(roadLine, road);
    cdt.insertConstraint(riverLine, river);
    cdt.finalize();
    TinData tin = cdt.toTinData();
    tin.crs = "EPSG:26912";
    ingest::writeTinFile(dir / "plane.tin", tin);
    ingest::TileJobOptions options;
    options.tiler.tolerance = 0.5;
    options.tiler.maxZoom = 2;
    ingest::runTileJob(tin, (dir / "plane.tin").string(), dir / "plane.3dtiles", options);
    return dir / "plane.3dtiles";
  }();
  return path;
}

/// A viewer folder made in code: pages, a hidden file, npm manifests, the
/// four library trees (one file each, a wasm), and a folder linked to a
/// secret outside the root.
fs::path fakeViewer() {
  static const fs::path root = [] {
    const auto base = scratchDir("viewer-assets-" + std::to_string(::getpid()));
    const auto write = [](const fs::path& p, const std::string& text) {
      fs::create_directories(p.parent_path());
      std::ofstream(p, std::ios::binary) << text;
    };
    const fs::path r = base / "viewer";
    write(r / "index.html", "<!doctype html><title>cesium page</title>" + std::string(2000, ' '));
    write(r / "three.html", "<!doctype html><title>three page</title>");
    write(r / "viewer.js", "console.log('viewer');");
    write(r / ".secret.js", "hidden");
    write(r / "package.json", "{}");
    write(r / "notes.md", "no type");
    write(r / "node_modules/cesium/Build/Cesium/Cesium.js",
          "var Cesium = {};" + std::string(3000, ';'));
    write(r / "node_modules/cesium/Build/Cesium/Workers/createGeometry.js", "self.x = 1;");
    write(r / "node_modules/cesium/Build/Cesium/.cache/x.js", "hidden");
    write(r / "node_modules/cesium/package.json", "{\"name\": \"cesium\"}");
    write(r / "node_modules/three/build/three.module.js", "export const REVISION = '0';");
    write(r / "node_modules/three/examples/jsm/libs/draco/gltf/draco_decoder.wasm",
          std::string("\0asm", 4));
    write(r / "node_modules/3d-tiles-renderer/build/index.three.js", "export {};");
    write(base / "secret.txt", "outside the root");
    fs::create_directory_symlink(base, r / "node_modules/cesium/Build/Cesium/outside");
    fs::create_symlink(base / "secret.txt", r / "node_modules/cesium/Build/Cesium/linked.txt");
    fs::create_symlink(base / "secret.txt", r / "linked.js");
    return r;
  }();
  return root;
}

server::TileServerOptions optionsFor(const fs::path& store) {
  auto o = RunningServer::defaults();
  o.stores = {store};
  return o;
}

TEST(ViewerRoutes, SlopeAndAspectAreThePlanesByHand) {
  RunningServer server(optionsFor(planeStore()));
  char target[160];
  std::snprintf(target, sizeof target, "/tilesets/plane/elevation?x=%.17g&y=%.17g", kX0 + 310.5,
                kY0 + 220.25);
  const auto r = httpGet(server.port(), target);
  ASSERT_EQ(r.status, 200) << r.body;
  const auto e = json::parse(r.body);
  // ∇z = (0.1, 0.2): slope atan(√0.05) = 12.604°; downhill (−0.1, −0.2) faces
  // atan2(−0.1, −0.2) = 206.565° clockwise from grid north.
  const double slope = std::atan(std::sqrt(0.1 * 0.1 + 0.2 * 0.2)) * 180 / std::numbers::pi;
  const double aspect = 180 + std::atan2(0.1, 0.2) * 180 / std::numbers::pi;
  EXPECT_NEAR(e["z"].get<double>(), planeZ(kX0 + 310.5, kY0 + 220.25), 1e-9);
  EXPECT_NEAR(e["slope"].get<double>(), slope, 1e-9);
  EXPECT_NEAR(e["slope"].get<double>(), 12.604382077, 1e-6);
  EXPECT_NEAR(e["aspect"].get<double>(), aspect, 1e-9);
  EXPECT_NEAR(e["aspect"].get<double>(), 206.565051177, 1e-6);
  EXPECT_NEAR(e["ellipsoidalHeight"].get<double>(), e["z"].get<double>(), 1e-6);  // no geoid
}

TEST(ViewerRoutes, BreakLinesAreTheConstraintsChainedAsGeoJson) {
  RunningServer server(optionsFor(planeStore()));
  HttpConnection c(server.port());
  auto r = c.request("/tilesets/plane/lines.geojson");
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.header("content-type"), "application/geo+json");
  const auto g = json::parse(r.body);
  EXPECT_EQ(g["type"], "FeatureCollection");
  std::map<std::string, std::vector<json>> byKind;
  for (const auto& f : g["features"]) {
    EXPECT_EQ(f["type"], "Feature");
    EXPECT_EQ(f["geometry"]["type"], "LineString");
    byKind[f["properties"]["kind"].get<std::string>()].push_back(f);
  }
  ASSERT_EQ(byKind["road"].size(), 1u);  // one chain each: the CDT split them, the route joins them
  ASSERT_EQ(byKind["river"].size(), 1u);
  EXPECT_EQ(byKind["road"][0]["properties"]["source"], "road.geojson, feature 0");
  // Every vertex back in the project CRS lies on the plane at the height the
  // line carries; the ends are the input's ends.
  const auto check = [&](const json& feature, Point2 first, Point2 last, std::size_t atLeast) {
    const auto& coordinates = feature["geometry"]["coordinates"];
    ASSERT_GE(coordinates.size(), atLeast);
    std::vector<Point2> xy;
    for (const auto& p : coordinates) {
      char t[160];
      std::snprintf(t, sizeof t, "/tilesets/plane/elevation?lon=%.17g&lat=%.17g",
                    p[0].get<double>(), p[1].get<double>());
      const auto e = json::parse(c.request(t).body);
      EXPECT_NEAR(p[2].get<double>(), planeZ(e["x"], e["y"]), 2e-3);
      xy.push_back({e["x"].get<double>(), e["y"].get<double>()});
    }
    const bool forward = std::hypot(xy.front().x - first.x, xy.front().y - first.y) < 0.01;
    const Point2 a = forward ? xy.front() : xy.back(), b = forward ? xy.back() : xy.front();
    EXPECT_NEAR(a.x, first.x, 0.01);
    EXPECT_NEAR(a.y, first.y, 0.01);
    EXPECT_NEAR(b.x, last.x, 0.01);
    EXPECT_NEAR(b.y, last.y, 0.01);
  };
  check(byKind["road"][0], {kX0 + 60, kY0 + 110}, {kX0 + 540, kY0 + 130}, 3);
  check(byKind["river"][0], {kX0 + 110, kY0 + 520}, {kX0 + 480, kY0 + 260}, 4);

  const std::string etag = r.header("etag");
  EXPECT_FALSE(etag.empty());
  EXPECT_EQ(c.request("/tilesets/plane/lines.geojson", "If-None-Match: " + etag + "\r\n").status,
            304);
  r = c.request("/tilesets/plane/lines.geojson", "Accept-Encoding: gzip\r\n");
  EXPECT_EQ(r.header("content-encoding"), "gzip");
  EXPECT_EQ(json::parse(gunzip(r.body)), g);
  r = c.request("/tilesets/plane/lines.geojson", "", "HEAD");
  EXPECT_EQ(r.status, 200);
  EXPECT_TRUE(r.body.empty());
}

TEST(ViewerRoutes, BreakLinesOfAStoreWithoutItsTinAre404) {
  const auto store = testStoreCopy("viewer-no-tin", "bare.3dtiles", [](const std::string& k) {
    return k != "tinsmith/terrain.tin";
  });
  RunningServer server(optionsFor(store));
  const auto r = httpGet(server.port(), "/tilesets/bare/lines.geojson");
  EXPECT_EQ(r.status, 404);
  EXPECT_NE(r.body.find("no break lines"), std::string::npos);
}

class ViewerFiles : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto o = RunningServer::defaults();
    o.service.viewer = std::make_shared<const server::ViewerAssets>(fakeViewer());
    server_ = new RunningServer(std::move(o));
  }
  static void TearDownTestSuite() { delete server_; }
  static HttpResponse get(const std::string& target, const std::string& headers = "") {
    return httpGet(server_->port(), target, headers);
  }
  static inline RunningServer* server_ = nullptr;
};

TEST_F(ViewerFiles, PagesAndLibrariesWithTheirTypesAndCaching) {
  auto r = get("/");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.header("content-type"), "text/html; charset=utf-8");
  EXPECT_NE(r.body.find("cesium page"), std::string::npos);
  EXPECT_EQ(r.header("cache-control"), "no-cache");
  EXPECT_EQ(get("/", "If-None-Match: " + r.header("etag") + "\r\n").status, 304);
  r = get("/", "Accept-Encoding: gzip\r\n");
  EXPECT_EQ(r.header("content-encoding"), "gzip");
  EXPECT_NE(gunzip(r.body).find("cesium page"), std::string::npos);

  r = get("/three");
  EXPECT_NE(r.body.find("three page"), std::string::npos);
  r = get("/viewer/lib/cesium/Cesium.js");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.header("content-type"), "text/javascript; charset=utf-8");
  EXPECT_EQ(r.header("cache-control"), server::kLibraryCacheControl);
  EXPECT_EQ(
      get("/viewer/lib/cesium/Cesium.js", "If-None-Match: " + r.header("etag") + "\r\n").status,
      304);
  r = get("/viewer/lib/three/examples/jsm/libs/draco/gltf/draco_decoder.wasm");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.header("content-type"), "application/wasm");
  EXPECT_EQ(r.body, std::string("\0asm", 4));
  EXPECT_EQ(get("/viewer/lib/cesium/Workers/createGeometry.js").status, 200);
  EXPECT_EQ(get("/viewer/lib/three/build/three.module.js").status, 200);
  EXPECT_EQ(get("/viewer/viewer.js").header("cache-control"), "no-cache");
}

TEST_F(ViewerFiles, NothingOutsideTheTableIsServed) {
  for (const char* target :
       {"/viewer/.secret.js", "/viewer/package.json", "/viewer/notes.md",
        "/viewer/lib/cesium/.cache/x.js", "/viewer/lib/cesium/package.json",
        "/viewer/lib/cesium/outside/secret.txt", "/viewer/lib/cesium/linked.txt",
        "/viewer/linked.js", "/viewer/lib/cesium", "/viewer/index.htm",
        "/viewer/lib/cesium/cesium.js", "/viewer"})
    EXPECT_EQ(get(target).status, 404) << target;
  for (const char* target : {"/viewer/lib/cesium/../../../secret.txt",
                             "/viewer/lib/%2e%2e/secret.txt", "/viewer/lib%2fcesium%2fCesium.js",
                             "/viewer/viewer.js%00.png", "/viewer/lib/cesium/..%5c..%5csecret.txt"})
    EXPECT_EQ(get(target).status, 400) << target;
}

TEST(ViewerRoutesWithout, TheIndexSaysWhatToInstall) {
  RunningServer server;
  auto r = httpGet(server.port(), "/");
  ASSERT_EQ(r.status, 200);
  EXPECT_NE(r.body.find("The viewer is not installed"), std::string::npos);
  EXPECT_NE(r.body.find("tools/setup.sh"), std::string::npos);
  EXPECT_NE(r.body.find("/tilesets/hill/tileset.json"), std::string::npos);
  EXPECT_EQ(httpGet(server.port(), "/viewer/lib/cesium/Cesium.js").status, 404);
}

TEST(ViewerRoutesWithout, AViewerFolderWithoutIndexIsRefused) {
  const auto dir = scratchDir("viewer-empty-" + std::to_string(::getpid()));
  EXPECT_THROW(server::ViewerAssets{dir}, Error);
  EXPECT_FALSE(server::findViewerRoot({dir, dir / "missing"}).has_value());
  EXPECT_EQ(server::findViewerRoot({dir, fakeViewer()}), fakeViewer());
}

TEST(BasePath, NormalisedOrRefused) {
  EXPECT_EQ(server::normalizeBasePath(""), "");
  EXPECT_EQ(server::normalizeBasePath("/"), "");
  EXPECT_EQ(server::normalizeBasePath("/terrain/demo/"), "/terrain/demo");
  EXPECT_EQ(server::normalizeBasePath("terrain"), "/terrain");
  for (const char* bad : {"/a/../b", "/a//b", "/a b", "/a/./b", "/a%2fb", "/a?x"})
    EXPECT_THROW(server::normalizeBasePath(bad), Error) << bad;
}

TEST(BasePath, EveryRouteAnswersUnderThePrefixOnly) {
  auto o = RunningServer::defaults();
  o.service.basePath = "/terrain/demo";
  o.service.viewer = std::make_shared<const server::ViewerAssets>(fakeViewer());
  RunningServer server(std::move(o));
  const auto get = [&](const std::string& t) { return httpGet(server.port(), t); };
  auto r = get("/terrain/demo");
  EXPECT_EQ(r.status, 301);
  EXPECT_EQ(r.header("location"), "/terrain/demo/");
  EXPECT_EQ(get("/terrain/demo?imagery=x").header("location"), "/terrain/demo/?imagery=x");
  EXPECT_NE(get("/terrain/demo/").body.find("cesium page"), std::string::npos);
  EXPECT_EQ(get("/terrain/demo/viewer/lib/cesium/Cesium.js").status, 200);
  r = get("/terrain/demo/tilesets");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(json::parse(r.body)["tilesets"][0]["links"]["tileset"],
            "/terrain/demo/tilesets/hill/tileset.json");
  EXPECT_EQ(get("/terrain/demo/tilesets/hill/tileset.json").status, 200);
  EXPECT_EQ(get("/terrain/demo/tilesets/hill/lines.geojson").status, 200);
  for (const char* outside :
       {"/", "/tilesets", "/terrain", "/terrain/demox", "/terrain/demo2/tilesets"})
    EXPECT_EQ(get(outside).status, 404) << outside;
}

}  // namespace
}  // namespace tinsmith::test
