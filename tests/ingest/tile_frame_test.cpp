// The local (ENU) content frame end to end: a job with frame = local writes
// tiles whose decoded positions, placed by their root node, are the tile
// meshes' vertices in the east-north-up frame tileset.json declares
// (extras.tinsmith.enuOrigin), within the Draco quantization bound each tile
// records. (tests/core/encode_test.cpp checks the frames and the root matrix
// alone; this checks what a three.js scene reading the store would place.)
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/encode/frames.hpp"
#include "core/encode/glb.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tiler.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;

/// 600 m of jittered spot heights over a ridge at Red Butte, NAD83 / UTM 12N.
TinData ridgeTin() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-6, 6);
  std::vector<Point3> points;
  for (int j = 0; j <= 20; ++j) {
    for (int i = 0; i <= 20; ++i) {
      const double x = i * 30.0 + ((i % 20) ? jitter(rng) : 0);
      const double y = j * 30.0 + ((j % 20) ? jitter(rng) : 0);
      points.push_back({434000 + x, 4516000 + y, 1700 + 60 * std::exp(-std::pow(x - y, 2) / 4e4)});
    }
  }
  cdt.insertPoints(points, spots);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  tin.crs = "EPSG:26912";
  return tin;
}

double distance(const Point3& a, const Point3& b) {
  return std::hypot(a.x - b.x, a.y - b.y, a.z - b.z);
}

/// Where a decoded position lands in the tileset's frame: the root node's
/// matrix, then 3D Tiles' y-up → z-up turn (x, y, z) ↦ (x, −z, y).
Point3 placed(const encode::Matrix4& m, const std::array<float, 3>& p) {
  const double x = p[0], y = p[1], z = p[2];
  const Point3 q{m[0] * x + m[4] * y + m[8] * z + m[12], m[1] * x + m[5] * y + m[9] * z + m[13],
                 m[2] * x + m[6] * y + m[10] * z + m[14]};
  return {q.x, -q.z, q.y};
}

TEST(LocalFrame, DecodedTilesAreTheTileMeshesInTheDeclaredEnuFrame) {
  const TinData tin = ridgeTin();
  TileJobOptions options;
  options.tiler.tolerance = 0.2;
  options.tiler.maxTriangles = 256;
  options.frame = tiles::ContentFrame::Local;
  options.compression = encode::Compression::Draco;
  const fs::path store = test::scratchDir("local-frame") / "ridge";
  runTileJob(tin, "ridge.tin", store, options);

  // The frame tileset.json declares: ENU at the pyramid's centre, z = 0.
  const auto tileset = nlohmann::json::parse(test::readFile(store / "tileset.json"));
  EXPECT_FALSE(tileset["root"].contains("transform"));
  ASSERT_TRUE(tileset["root"]["boundingVolume"].contains("box"));
  const auto declared = tileset["extras"]["tinsmith"]["enuOrigin"];
  ASSERT_EQ(declared.size(), 3u) << tileset["extras"].dump();
  const encode::Geodetic origin{declared[0], declared[1], declared[2]};
  const tiles::Tiler tiler(tin, options.tiler);
  const ProjGeoReference geo(tin.crs, "");
  const double half = 0.5 * tiler.geometry().size();
  const Point3 centre{tiler.geometry().origin().x + half, tiler.geometry().origin().y + half, 0.0};
  encode::Geodetic expectedOrigin;
  geo.toGeodetic({&centre, 1}, {&expectedOrigin, 1});
  EXPECT_NEAR(origin.lon, expectedOrigin.lon, 1e-12);
  EXPECT_NEAR(origin.lat, expectedOrigin.lat, 1e-12);
  EXPECT_NEAR(origin.height, 0.0, 1e-6);
  const encode::EnuFrame enu(origin);

  std::size_t tilesChecked = 0;
  for (const auto& entry : fs::recursive_directory_iterator(store / "tiles")) {
    if (entry.path().extension() != ".glb") continue;
    const std::string bytes = test::readFile(entry.path());
    const encode::DecodedGlb glb = encode::decodeGlb(bytes, entry.path().string());
    ASSERT_TRUE(glb.draco);
    const auto record = tiles::recordFromExtras(glb.assetExtras);
    ASSERT_TRUE(record && record->local) << entry.path();
    // Draco's bound, plus float rounding of positions a few hundred metres
    // from the tile's centre.
    const double bound = record->positionErrorBound + 1e-4;
    ASSERT_GT(record->positionErrorBound, 0.0);

    // The tile's mesh, placed independently: project CRS → WGS84 → ENU.
    const tiles::TileSurface surface = tiler.buildTile(record->id);
    ASSERT_FALSE(surface.empty()) << record->id.name();
    std::vector<encode::Geodetic> g(surface.vertices.size());
    geo.toGeodetic(surface.vertices, g);
    std::vector<Point3> expected;
    for (const auto& v : g) expected.push_back(enu.fromGeodetic(v));

    std::vector<Point3> decoded;
    for (const auto& p : glb.mesh.positions) decoded.push_back(placed(glb.rootMatrix, p));
    // Every mesh vertex is in the tile where it should be.
    for (std::size_t i = 0; i < expected.size(); ++i) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const auto& d : decoded) nearest = std::min(nearest, distance(expected[i], d));
      EXPECT_LE(nearest, bound) << record->id.name() << " vertex " << i;
    }
    // Every decoded position is a mesh vertex or a skirt vertex straight
    // below one (1 km from the origin, "down" in the project CRS and in ENU
    // differ by under 1e-4 of the skirt's depth), and lies in the tile's box.
    std::size_t skirt = 0;
    for (const auto& d : decoded) {
      bool onMesh = false, belowMesh = false;
      for (const auto& e : expected) {
        onMesh = onMesh || distance(d, e) <= bound;
        belowMesh = belowMesh || (std::hypot(d.x - e.x, d.y - e.y) <= bound + 1e-3 && d.z < e.z);
      }
      EXPECT_TRUE(onMesh || belowMesh) << record->id.name() << " at " << d.x << " " << d.y;
      skirt += onMesh ? 0 : 1;
      const auto& box = record->box;
      EXPECT_LE(std::abs(d.x - box[0]), box[3] + bound);
      EXPECT_LE(std::abs(d.y - box[1]), box[7] + bound);
      EXPECT_LE(std::abs(d.z - box[2]), box[11] + bound);
    }
    EXPECT_GT(skirt, 0u) << record->id.name();
    ++tilesChecked;
  }
  EXPECT_GT(tilesChecked, 1u);
}

TEST(TileUnits, ATinInACrsOfFeetIsRefusedBeforeAnyTile) {
  TinData tin = ridgeTin();
  tin.crs = "EPSG:2227";  // California zone 3, US survey feet
  const fs::path dir = test::scratchDir("tile-feet");
  try {
    runTileJob(tin, "feet.tin", dir / "feet.3dtiles", TileJobOptions{});
    ADD_FAILURE() << "a TIN in feet was tiled as metres";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("US survey foot"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("feet.tin"), std::string::npos) << e.what();
  }
  EXPECT_EQ(test::filesIn(dir), 0u);
}

}  // namespace
}  // namespace tinsmith::ingest
