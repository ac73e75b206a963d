// Tile seams: two tiles that share a side have the same vertices along it, at
// the same heights — here where a break line only touches the side (a V whose
// tip is on it, both arms in one tile), which the tile without the arms
// dropped, leaving a crack of 0.42 m at the tip.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <tuple>

#include "core/tiles/tiler.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;

/// The (along, z) of a tile's vertices on one side, exactly.
std::set<std::pair<double, double>> sideVertices(const tiles::TileSurface& t, std::uint8_t side) {
  std::set<std::pair<double, double>> out;
  const bool vertical = side == tiles::kSideWest || side == tiles::kSideEast;
  for (std::size_t v = 0; v < t.vertices.size(); ++v)
    if (t.flags[v] & side)
      out.insert({vertical ? t.vertices[v].y : t.vertices[v].x, t.vertices[v].z});
  return out;
}

TEST(TileSeams, ABreakLineThatOnlyTouchesASideIsOnBothTilesOfIt) {
  const fs::path dir = test::scratchDir("tile-seams");
  // The tip (500500, 4500405) lies on the side x = 500500 of the zoom-1 tiles.
  std::ofstream(dir / "v.geojson")
      << R"({"type":"FeatureCollection","features":[{"type":"Feature","properties":{},)"
      << R"("geometry":{"type":"LineString","coordinates":[[500305,4500205,25.5],)"
      << R"([500500,4500405,45.55],[500305,4500605,45.5]]}}]})";
  const auto r = test::runTinsmith(
      "tin --points 'synthetic:grid?nx=101&ny=101&spacing=10&x0=500000&y0=4500000&surface=plane"
      "&scale=100&noise=0.3' --breaklines " +
      (dir / "v.geojson").string() + " --crs EPSG:32612 -q -o " + (dir / "v.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const TinData tin = readTinFile(dir / "v.tin");
  tiles::TilerOptions options;
  options.tolerance = 0.2;
  options.maxTriangles = 256;
  const tiles::Tiler tiler(tin, options);
  ASSERT_GE(tiler.finestZoom(), 1);

  std::size_t sidesCompared = 0;
  bool tipSeen = false;
  for (int z = 1; z <= std::min(tiler.finestZoom(), 3); ++z) {
    const std::uint32_t n = 1U << z;
    // Each pair of tiles with a side in common: west–east, then south–north.
    for (const bool northward : {false, true}) {
      for (std::uint32_t y = 0; y < n; ++y) {
        for (std::uint32_t x = 0; x < n; ++x) {
          if ((northward ? y : x) + 1 >= n) continue;
          const tiles::TileSurface first = tiler.buildTile({z, x, y});
          const tiles::TileSurface second =
              tiler.buildTile(northward ? tiles::TileId{z, x, y + 1} : tiles::TileId{z, x + 1, y});
          if (first.empty() || second.empty()) continue;
          const auto a = sideVertices(first, northward ? tiles::kSideNorth : tiles::kSideEast);
          const auto b = sideVertices(second, northward ? tiles::kSideSouth : tiles::kSideWest);
          std::string diff;
          for (const auto& [u, h] : a)
            if (!b.count({u, h}))
              diff += " first has (" + std::to_string(u) + ", " + std::to_string(h) + ")";
          for (const auto& [u, h] : b)
            if (!a.count({u, h}))
              diff += " second has (" + std::to_string(u) + ", " + std::to_string(h) + ")";
          EXPECT_TRUE(diff.empty())
              << "side between " << first.id.name() << " and " << second.id.name() << ":" << diff;
          ++sidesCompared;
          if (!northward && first.bounds.x1 == 500500.0) {
            for (const auto& [along, h] : a)
              tipSeen = tipSeen || (along == 4500405.0 && h == 45.55);
          }
        }
      }
    }
  }
  EXPECT_GT(sidesCompared, 0u);
  EXPECT_TRUE(tipSeen) << "the V's tip is not on the side x = 500500 as expected";
}

}  // namespace
}  // namespace tinsmith::ingest
