// Tile regions anywhere on Earth: every decoded position of every tile lies in
// the region its tile declares, and every region in its parent's, read with
// 3D Tiles' eastward longitudes (east < west crosses ±180°) — on a TIN across
// the antimeridian (UTM 60N) and one around the North Pole (EPSG:3995); the
// root's geometricError stays of the TIN's size. Also the longitude ranges
// themselves.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/encode/frames.hpp"
#include "core/encode/glb.hpp"
#include "core/tiles/lon_range.hpp"
#include "core/tiles/tile_content.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;
using tiles::LonRange;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

/// Whether `lon` is in the eastward range, within `slack` radians.
bool inRange(const LonRange& r, double lon, double slack) {
  if (tiles::isEveryLongitude(r)) return true;
  double offset = lon - r.west;
  offset = std::remainder(offset, 2 * kPi);
  if (offset < -slack) offset += 2 * kPi;
  return offset <= tiles::lonSpan(r) + slack;
}

bool containsRange(const LonRange& outer, const LonRange& inner, double slack) {
  if (tiles::isEveryLongitude(outer)) return true;
  if (tiles::isEveryLongitude(inner)) return false;
  double offset = std::remainder(inner.west - outer.west, 2 * kPi);
  if (offset < -slack) offset += 2 * kPi;
  return offset + tiles::lonSpan(inner) <= tiles::lonSpan(outer) + slack;
}

TEST(LonRange, RangesAcrossTheAntimeridianAndTheirUnions) {
  const double lons[] = {179.5 * kDeg, -179.8 * kDeg, 179.9 * kDeg};
  const LonRange r = tiles::lonRangeAround(179.9 * kDeg, lons);
  EXPECT_NEAR(r.west, 179.5 * kDeg, 1e-12);
  EXPECT_NEAR(r.east, -179.8 * kDeg, 1e-12);
  EXPECT_NEAR(tiles::lonSpan(r), 0.7 * kDeg, 1e-12);
  // A range on either side joined across ±180°, not around the globe.
  const LonRange u = tiles::lonUnion({170 * kDeg, 179 * kDeg}, {-179 * kDeg, -170 * kDeg});
  EXPECT_NEAR(u.west, 170 * kDeg, 1e-12);
  EXPECT_NEAR(u.east, -170 * kDeg, 1e-12);
  // Overlapping, nested, and far apart (the shorter way round).
  const LonRange nested = tiles::lonUnion({0, 1}, {0.2, 0.5});
  EXPECT_DOUBLE_EQ(nested.west, 0);
  EXPECT_DOUBLE_EQ(nested.east, 1);
  const LonRange apart = tiles::lonUnion({-3.0, -2.9}, {2.9, 3.0});
  EXPECT_DOUBLE_EQ(apart.west, 2.9);
  EXPECT_DOUBLE_EQ(apart.east, -2.9);
  EXPECT_TRUE(tiles::isEveryLongitude(tiles::lonUnion({}, {0, 1})));
  EXPECT_TRUE(tiles::isEveryLongitude(tiles::lonUnion({0, 3}, {3, 0.1})));
}

struct Tiled {
  nlohmann::json tileset;
  std::map<std::string, tiles::TileRecord> records;
  std::size_t positions = 0;
};

/// Tiles a synthetic grid in `crs` without compression and checks each
/// decoded position against its tile's region.
Tiled tileAndCheck(const std::string& name, const std::string& grid, const std::string& crs) {
  const auto dir = scratchDir("tile-regions-" + name);
  const auto tin = dir / "t.tin";
  auto r = runTinsmith("tin --points '" + grid + "' --crs " + crs + " -q -o " + tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  r = runTinsmith("tile " + tin.string() + " --compression none --max-triangles 2048 -q -o " +
                  (dir / "store").string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  Tiled out;
  out.tileset = nlohmann::json::parse(readFile(dir / "store" / "tileset.json"));
  for (const auto& entry : fs::recursive_directory_iterator(dir / "store" / "tiles")) {
    if (entry.path().extension() != ".glb") continue;
    const auto glb = encode::decodeGlb(readFile(entry.path()), entry.path().string());
    const auto record = tiles::recordFromExtras(glb.assetExtras);
    EXPECT_TRUE(record) << entry.path();
    if (!record) continue;
    const auto& region = record->region;
    const LonRange lon{region[0], region[2]};
    const auto& m = glb.rootMatrix;
    for (const auto& p : glb.mesh.positions) {
      // glTF is y-up: the node matrix, then y-up to z-up, is ECEF.
      const double x = p[0], y = p[1], z = p[2];
      const Point3 q{m[0] * x + m[4] * y + m[8] * z + m[12], m[1] * x + m[5] * y + m[9] * z + m[13],
                     m[2] * x + m[6] * y + m[10] * z + m[14]};
      const encode::Geodetic g = encode::ecefToGeodetic({q.x, -q.z, q.y});
      const double slack = 1e-7;  // about a centimetre of float rounding
      EXPECT_TRUE(inRange(lon, g.lon * kDeg, slack))
          << record->id.name() << ": lon " << g.lon << " outside " << region[0] / kDeg << ".."
          << region[2] / kDeg;
      EXPECT_GE(g.lat * kDeg, region[1] - slack) << record->id.name();
      EXPECT_LE(g.lat * kDeg, region[3] + slack) << record->id.name();
      ++out.positions;
    }
    out.records[record->id.name()] = *record;
  }
  return out;
}

/// Every tile's region in its parent's (tileset.json's, grown from the tiles).
void expectNested(const nlohmann::json& tile, const std::string& path) {
  const auto& r = tile["boundingVolume"]["region"];
  for (const auto& child : tile.value("children", nlohmann::json::array())) {
    const auto& c = child["boundingVolume"]["region"];
    EXPECT_TRUE(containsRange({r[0], r[2]}, {c[0], c[2]}, 1e-12))
        << path << " " << c << " in " << r;
    EXPECT_LE(r[1].get<double>(), c[1].get<double>()) << path;
    EXPECT_GE(r[3].get<double>(), c[3].get<double>()) << path;
    expectNested(child, path + "/child");
  }
}

TEST(TileRegions, AcrossTheAntimeridian) {
  // 80 km of UTM 60N centred on 180°.
  const Tiled t = tileAndCheck(
      "antimeridian",
      "synthetic:grid?nx=81&ny=81&spacing=1000&x0=700000&y0=4940000&surface=hill&scale=300",
      "EPSG:32660");
  EXPECT_GT(t.positions, 1000u);
  const auto& root = t.tileset["root"];
  const auto& region = root["boundingVolume"]["region"];
  EXPECT_GT(region[0].get<double>(), region[2].get<double>()) << "the root crosses ±180°";
  EXPECT_LT(tiles::lonSpan({region[0], region[2]}), 2 * kDeg);
  EXPECT_LT(t.tileset["geometricError"].get<double>(), 500000.0);
  expectNested(root, "root");
  // Some tile lies across the line itself.
  bool crossing = false;
  for (const auto& [name, record] : t.records)
    crossing = crossing || record.region[0] > record.region[2];
  EXPECT_TRUE(crossing);
}

TEST(TileRegions, AroundTheNorthPole) {
  const Tiled t = tileAndCheck(
      "pole", "synthetic:grid?nx=81&ny=81&spacing=1000&x0=-40000&y0=-40000&surface=hill&scale=300",
      "EPSG:3995");
  EXPECT_GT(t.positions, 1000u);
  const auto& region = t.tileset["root"]["boundingVolume"]["region"];
  EXPECT_TRUE(tiles::isEveryLongitude({region[0], region[2]})) << region;
  EXPECT_DOUBLE_EQ(region[3].get<double>(), kPi / 2);
  EXPECT_LT(t.tileset["geometricError"].get<double>(), 200000.0);
  expectNested(t.tileset["root"], "root");
}

}  // namespace
}  // namespace tinsmith::test
