// Declared errors true after encoding: every tile is decoded as a client
// decodes it (Draco, the root node's matrix, straight triangles in ECEF),
// taken back to the project CRS, and held to what its record declares —
//   - on a mesa with 500 m walls over 1 m (Draco's rounding, up to a few
//     millimetres, moves a wall's surface by metres vertically): the 3-D
//     distance from each decoded triangle (corners, edge middles, centre) to
//     the TIN within the tile's geometricError, which was the error measured
//     before encoding (0.001 m where the decoded surface sits farther off);
//   - on a flat 20 km TIN (a chord of 20 km sags 8 m below the ground): every
//     decoded position and chord middle inside the tile's region and within
//     the tolerance of the TIN (7 m below it and outside the region before).
// A third test measures a store given in TINSMITH_MEASURE_STORE (its TIN in
// TINSMITH_MEASURE_TIN; ellipsoidal heights) and prints, per zoom, the worst
// decoded distance against the declared error; skipped without them.
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>

#include "core/encode/frames.hpp"
#include "core/encode/glb.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/tile_content.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/test_terrain.hpp"
#include "tests/support/tin_distance.hpp"

namespace tinsmith::ingest {
namespace {

using test::distanceToTin;
using test::pointTriangleDistance;
using test::ToProject;

namespace fs = std::filesystem;
constexpr double kDeg = std::numbers::pi / 180.0;

/// A tile as a client draws it: ECEF positions, its surface triangles (the
/// skirts, which hang below the sides, apart) and its record.
struct DecodedTile {
  tiles::TileRecord record;
  std::vector<Point3> ecef;
  std::vector<std::array<std::uint32_t, 3>> surface, skirts;
};

DecodedTile decodeTile(const fs::path& file) {
  const auto glb = encode::decodeGlb(test::readFile(file), file.string());
  DecodedTile out;
  const auto record = tiles::recordFromExtras(glb.assetExtras);
  EXPECT_TRUE(record) << file;
  if (record) out.record = *record;
  const auto& m = glb.rootMatrix;
  for (const auto& p : glb.mesh.positions) {
    // glTF is y-up: the node matrix, then y-up to z-up, is ECEF.
    const double x = p[0], y = p[1], z = p[2];
    const Point3 q{m[0] * x + m[4] * y + m[8] * z + m[12], m[1] * x + m[5] * y + m[9] * z + m[13],
                   m[2] * x + m[6] * y + m[10] * z + m[14]};
    out.ecef.push_back({q.x, -q.z, q.y});
  }
  // A skirt triangle has two corners one above the other, within the
  // rounding: each is rounded on its own, by up to the record's
  // positionErrorBound (1 % of the tolerance on a coarse tile) or, without
  // Draco, float32's step at its distance from the centre. Two surface
  // vertices that close across, and steeper than 2:1, would be a wall
  // narrower than the rounding.
  double farthest = 0.0;
  for (const auto& p : glb.mesh.positions)
    farthest = std::max(farthest, std::hypot(double(p[0]), double(p[1]), double(p[2])));
  const double rounding = 0.05 + 4 * out.record.positionErrorBound + 5e-7 * farthest;
  const auto& ix = glb.mesh.indices;
  for (std::size_t t = 0; t + 2 < ix.size(); t += 3) {
    const std::array<std::uint32_t, 3> tri{ix[t], ix[t + 1], ix[t + 2]};
    bool skirt = false;
    for (int i = 0; i < 3; ++i) {
      const Point3& a = out.ecef[tri[i]];
      const Point3& b = out.ecef[tri[(i + 1) % 3]];
      const encode::Geodetic ga = encode::ecefToGeodetic(a), gb = encode::ecefToGeodetic(b);
      const double across = std::hypot((ga.lon - gb.lon) * kDeg * 6.4e6 * std::cos(ga.lat * kDeg),
                                       (ga.lat - gb.lat) * kDeg * 6.4e6);
      const double drop = std::abs(ga.height - gb.height);
      if (across < rounding && drop > 2 * across && drop > 1e-3) skirt = true;
    }
    (skirt ? out.skirts : out.surface).push_back(tri);
  }
  return out;
}

std::vector<DecodedTile> decodeStore(const fs::path& store) {
  std::vector<DecodedTile> out;
  for (const auto& entry : fs::recursive_directory_iterator(store / "tiles"))
    if (entry.path().extension() == ".glb") out.push_back(decodeTile(entry.path()));
  return out;
}

/// Points of each surface triangle a client draws: corners, edge middles and
/// centre, in ECEF (on the straight triangle).
std::vector<Point3> drawnPoints(const DecodedTile& tile) {
  std::vector<Point3> out;
  for (const auto& t : tile.surface) {
    const Point3& a = tile.ecef[t[0]];
    const Point3& b = tile.ecef[t[1]];
    const Point3& c = tile.ecef[t[2]];
    for (const auto& [u, v, w] : {std::array{1.0, 0.0, 0.0},
                                  {0.0, 1.0, 0.0},
                                  {0.0, 0.0, 1.0},
                                  {0.5, 0.5, 0.0},
                                  {0.0, 0.5, 0.5},
                                  {0.5, 0.0, 0.5},
                                  {1.0 / 3, 1.0 / 3, 1.0 / 3}}) {
      out.push_back(
          {u * a.x + v * b.x + w * c.x, u * a.y + v * b.y + w * c.y, u * a.z + v * b.z + w * c.z});
    }
  }
  return out;
}

/// Per tile: the largest 3-D distance from what it draws to the TIN.
struct Measured {
  tiles::TileRecord record;
  double worst = 0.0;
};

std::vector<Measured> measureStore(const fs::path& store, const TinData& tin) {
  const tiles::TinIndex index(tin);
  const ToProject toProject(tin.crs);
  std::vector<Measured> out;
  std::vector<std::uint32_t> scratch;
  for (const DecodedTile& tile : decodeStore(store)) {
    Measured m{tile.record, 0.0};
    for (const Point3& q : drawnPoints(tile)) {
      const Point3 p = toProject(encode::ecefToGeodetic(q));
      const auto d = distanceToTin(p, index, std::max(1.0, 4 * tile.record.error), scratch);
      if (d) m.worst = std::max(m.worst, *d);
    }
    out.push_back(m);
  }
  return out;
}

fs::path makeTin(const fs::path& dir, const std::string& inputs) {
  const fs::path tin = dir / "t.tin";
  const auto r = test::runTinsmith("tin " + inputs + " --crs EPSG:32612 -q -o " + tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return tin;
}

TEST(TileDecodedError, OnSteepWallsTheDecodedSurfaceIsWithinTheDeclaredError) {
  const fs::path dir = test::scratchDir("tile-decoded-mesa");
  // A mesa: its rim at 1500 m (r = 250 m), its foot at 1000 m one metre out
  // (r = 251 m), flat ground to r = 500 m.
  const fs::path tinPath = makeTin(
      dir,
      "--breaklines "
      "'synthetic:rings?n=1&width=1000&height=1000&z0=1000&interval=500&x0=500000&y0=4500000' "
      "'synthetic:rings?n=1&width=1004&height=1004&z0=500&interval=500&x0=499998&y0=4499998' "
      "'synthetic:rings?n=1&width=2000&height=2000&z0=500&interval=500&x0=499500&y0=4499500'");
  const auto r =
      test::runTinsmith("tile " + tinPath.string() + " --tolerance 0.5 --max-triangles 128 -q -o " +
                        (dir / "store").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const TinData tin = readTinFile(tinPath);
  const auto measured = measureStore(dir / "store", tin);
  ASSERT_GE(measured.size(), 5u);
  for (const auto& m : measured) {
    // The project CRS's scale (UTM: 0.9996 here) against the ground's metres.
    EXPECT_LE(m.worst, m.record.error * 1.001 + 1e-6)
        << "tile " << m.record.id.name() << ": drawn " << m.worst << " m from the TIN, declared "
        << m.record.error;
  }
}

TEST(TileDecodedError, AWideAreaRoundedToItsToleranceIsDrawnWithinTheDeclaredError) {
  // 1 500 km of CONUS Albers, a TIN vertex every 30 km: its tiles are
  // rounded to 1 % of their tolerance (5 cm to 1 m here, not 1 cm), their
  // chords sag metres below the ground, and Albers bends its straight lines.
  const fs::path dir = test::scratchDir("tile-decoded-wide");
  const fs::path tinPath = dir / "t.tin";
  ASSERT_EQ(test::runTinsmith("tin --points "
                              "'synthetic:grid?nx=51&ny=51&spacing=30000&x0=-2000000&y0=300000&"
                              "surface=hill&z0=300&scale=2000&noise=5' --crs EPSG:5070 -q -o " +
                              tinPath.string())
                .exitCode,
            0);
  const auto r =
      test::runTinsmith("tile " + tinPath.string() + " --tolerance 5 --max-triangles 4096 -q -o " +
                        (dir / "store").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto measured = measureStore(dir / "store", readTinFile(tinPath));
  ASSERT_GE(measured.size(), 21u);
  for (const auto& m : measured) {
    EXPECT_LE(m.worst, m.record.error * 1.001 + 1e-6)
        << "tile " << m.record.id.name() << ": drawn " << m.worst << " m from the TIN, declared "
        << m.record.error;
  }
  // The skirts are told apart from the surface, though their corners are
  // rounded apart by more than 5 cm: every tile has them (two triangles a
  // piece of its sides), and nothing else is counted as one.
  for (const DecodedTile& tile : decodeStore(dir / "store")) {
    EXPECT_GT(tile.record.positionErrorBound, 0.04) << tile.record.id.name();
    EXPECT_GT(tile.skirts.size(), tile.surface.size() / 8) << tile.record.id.name();
    EXPECT_EQ(tile.skirts.size() + tile.surface.size(), tile.record.triangles)
        << tile.record.id.name();
  }
}

TEST(TileDecodedError, AFlat20KmTinIsDrawnInsideItsRegionsAndWithinTolerance) {
  const fs::path dir = test::scratchDir("tile-decoded-flat");
  const fs::path tinPath = makeTin(
      dir,
      "--points "
      "'synthetic:grid?nx=21&ny=21&spacing=1000&x0=400000&y0=4000000&surface=flat&z0=1000'");
  const double tolerance = 1.0;
  const auto r = test::runTinsmith("tile " + tinPath.string() + " --tolerance 1 -q -o " +
                                   (dir / "store").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  std::size_t checked = 0;
  for (const DecodedTile& tile : decodeStore(dir / "store")) {
    const auto& region = tile.record.region;
    auto inRegion = [&](const Point3& q, const char* what) {
      const encode::Geodetic g = encode::ecefToGeodetic(q);
      const double slack = 1e-10;  // radians: 0.6 mm
      EXPECT_GE(g.lon * kDeg, region[0] - slack) << tile.record.id.name() << " " << what;
      EXPECT_LE(g.lon * kDeg, region[2] + slack) << tile.record.id.name() << " " << what;
      EXPECT_GE(g.lat * kDeg, region[1] - slack) << tile.record.id.name() << " " << what;
      EXPECT_LE(g.lat * kDeg, region[3] + slack) << tile.record.id.name() << " " << what;
      EXPECT_GE(g.height, region[4] - 1e-6) << tile.record.id.name() << " " << what;
      EXPECT_LE(g.height, region[5] + 1e-6) << tile.record.id.name() << " " << what;
      return g;
    };
    for (const auto& tris : {tile.surface, tile.skirts}) {
      for (const auto& t : tris) {
        for (int i = 0; i < 3; ++i) {
          const Point3& a = tile.ecef[t[i]];
          const Point3& b = tile.ecef[t[(i + 1) % 3]];
          inRegion(a, "corner");
          inRegion({0.5 * (a.x + b.x), 0.5 * (a.y + b.y), 0.5 * (a.z + b.z)}, "chord middle");
        }
      }
    }
    // The TIN is flat at 1000 m (ellipsoidal): what is drawn is within the
    // tolerance of it, and within the declared error.
    for (const Point3& q : drawnPoints(tile)) {
      const double off = std::abs(encode::ecefToGeodetic(q).height - 1000.0);
      EXPECT_LE(off, tile.record.error + 1e-6) << tile.record.id.name();
      EXPECT_LE(off, tolerance) << tile.record.id.name();
      ++checked;
    }
  }
  EXPECT_GT(checked, 0u);
}

TEST(TileDecodedError, TheTopFittedToZoomKsMosaicIsDrawnWithinItsDeclaredError) {
  // The rippled hill with its river, road and hole, tiled with the top above
  // zoom 2 fitted to zoom 2's mosaic (a TIN of 6 600 vertices over 1 024
  // points a square): what a tile above declares — against the mosaic, plus
  // the largest error of its zoom-2 tiles — bounds what it draws against
  // the TIN itself.
  const fs::path dir = test::scratchDir("tile-decoded-mosaic");
  TinData tin = test::rippledRiverTin();
  tin.crs = "EPSG:26912";
  TileJobOptions options;
  options.tiler.tolerance = 0.05;
  options.tiler.maxTriangles = 1024;
  options.tiler.mosaicPoints = 1024;
  options.threads = 2;
  runTileJob(tin, "ripple.tin", dir / "store", options);
  std::size_t above = 0;
  for (const auto& m : measureStore(dir / "store", tin)) {
    above += m.record.id.z < 2;
    EXPECT_LE(m.worst, m.record.error * 1.001 + 1e-6)
        << "tile " << m.record.id.name() << ": drawn " << m.worst << " m from the TIN, declared "
        << m.record.error;
  }
  EXPECT_EQ(above, 5u);
}

TEST(TileDecodedError, MeasureAStore) {
  const char* store = std::getenv("TINSMITH_MEASURE_STORE");
  const char* tinFile = std::getenv("TINSMITH_MEASURE_TIN");
  if (!store || !tinFile) GTEST_SKIP() << "set TINSMITH_MEASURE_STORE and TINSMITH_MEASURE_TIN";
  const TinData tin = readTinFile(tinFile);
  std::map<int, std::tuple<std::size_t, double, double, std::size_t>> zooms;
  for (const auto& m : measureStore(store, tin)) {
    auto& [tiles, worst, declared, over] = zooms[m.record.id.z];
    ++tiles;
    worst = std::max(worst, m.worst);
    declared = std::max(declared, m.record.error);
    if (m.worst > m.record.error * 1.001 + 1e-6) ++over;
  }
  for (const auto& [z, v] : zooms) {
    const auto& [tiles, worst, declared, over] = v;
    std::printf("zoom %d: %zu tiles, worst drawn %.4f m, largest declared %.4f m, %zu over\n", z,
                tiles, worst, declared, over);
  }
}

}  // namespace
}  // namespace tinsmith::ingest
