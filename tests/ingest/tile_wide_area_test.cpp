// Tiles of wide areas, as a national mosaic in a national projection makes
// them. How finely a tile's positions are quantized: within half of its
// zoom's encoding share (of its own error, when it misses its tolerance by
// far), never finer than a millionth of its width where the
// share allows, and without a 1 cm cap on wide coarse tiles (a 3 000 km tile at
// 1 cm took 29 bits a coordinate, and Draco's encoder an array of 2^29 counts
// for them: 1 GB and seconds a tile); a small tile keeps its fine steps. And
// chord sag where the projection bends straight lines: CONUS Albers across
// 3 000 km lies up to 13 % farther from the ground than the sphere says, and
// its tiles missed their tolerance by 9 % at every zoom, refining to the
// deepest zoom allowed; the tiler now plans with the radius that bounds it,
// and with a larger one where the projection stretches the ground (World
// Mercator at 75°N).
#include <gtest/gtest.h>

#include <cmath>

#include "core/cdt/cdt.hpp"
#include "core/encode/glb.hpp"
#include "core/tiles/chord_sag.hpp"
#include "core/tiles/pyramid_build.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tiler.hpp"
#include "ingest/tiles/proj_georeference.hpp"

namespace tinsmith::ingest {
namespace {

/// An n × n grid (n × rows, with rows) `spacing` metres apart from (x0, y0)
/// in `crs`, heights from `z`.
template <typename Height>
TinData projectedGrid(const std::string& crs, double x0, double y0, int n, double spacing, Height z,
                      int rows = 0) {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  std::vector<Point3> points;
  for (int j = 0; j < (rows > 0 ? rows : n); ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = i * spacing, y = j * spacing;
      points.push_back({x0 + x, y0 + y, z(x, y)});
    }
  }
  cdt.insertPoints(points, spots);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  tin.crs = crs;
  return tin;
}

/// The same in CONUS Albers (EPSG:5070), from (−2 000 km, 300 km).
template <typename Height>
TinData albersGrid(int n, double spacing, Height z) {
  return projectedGrid("EPSG:5070", -2000000, 300000, n, spacing, z);
}

struct Encoded {
  tiles::TileRecord record;
  double tolerance = 0;
  double width = 0;
};

Encoded encodeRoot(const TinData& tin, double tolerance) {
  const ProjGeoReference geo(tin.crs, "");
  tiles::TilerOptions options;
  options.tolerance = tolerance;
  options.maxTriangles = 512;
  options.threads = 1;
  options.geo = &geo;
  const tiles::Tiler tiler(tin, options);
  tiles::ContentOptions content;
  content.geo = &geo;
  const tiles::TileSurface root = tiler.buildTile({});
  EXPECT_FALSE(root.empty());
  const tiles::TileContent c =
      tiles::encodeTile(root, tiles::skirtDepth(tiler, root.id, root.error), content);
  // Draco decodes it.
  const encode::DecodedGlb glb = encode::decodeGlb(c.glb, "root");
  EXPECT_TRUE(glb.draco);
  return {c.record, root.tolerance, root.bounds.width()};
}

TEST(TileQuantization, AWideTileIsQuantizedToItsToleranceNotToACentimetre) {
  // 3 000 km of rolling hills at 20 m (the root's zoom: 80 m, or more).
  // The root's own error is mostly chord sag (512 triangles cannot follow
  // the Earth's curve across 3 000 km): its encoding is what counts here.
  const TinData hills = albersGrid(41, 75000, [](double x, double y) {
    return 500 + 800 * std::sin(x / 4e5) * std::cos(y / 3e5);
  });
  const Encoded wide = encodeRoot(hills, 20);
  EXPECT_NEAR(wide.width, 3e6, 1);
  EXPECT_LE(wide.record.positionErrorBound, 0.5 * tiles::kEncodingShare * wide.tolerance);
  EXPECT_GT(wide.record.positionErrorBound, 0.1);  // not 1 cm
  EXPECT_LE(wide.record.positionBits, 24);         // 29 at 1 cm

  // Flat, the tile measures no error, and a tenth of it would be no step at
  // all: a millionth of the width, 3 m, within the share of 5 km.
  const TinData flat = albersGrid(41, 75000, [](double, double) { return 200.0; });
  const Encoded plain = encodeRoot(flat, 5000);
  ASSERT_LE(plain.record.error, plain.tolerance);
  EXPECT_LE(plain.record.positionErrorBound, 1e-6 * plain.width);
  EXPECT_GT(plain.record.positionErrorBound, 0.5e-6 * plain.width);
  EXPECT_LE(plain.record.positionBits, 20);
  // Within its tolerance, where the share is tighter than the width's step,
  // the share rules: 200 km at 10 m.
  const TinData narrower = albersGrid(41, 5000, [](double, double) { return 200.0; });
  const Encoded tight = encodeRoot(narrower, 10);
  ASSERT_LE(tight.record.error, tight.tolerance);
  ASSERT_LT(0.5 * tiles::kEncodingShare * tight.tolerance, 1e-6 * tight.width);
  EXPECT_LE(tight.record.positionErrorBound, 0.5 * tiles::kEncodingShare * tight.tolerance);
  EXPECT_GT(tight.record.positionErrorBound, 0.02);
  // At 5 m, 512 triangles cannot follow the Earth's curve: the root misses
  // its tolerance by hundreds of metres of chord sag. Its steps follow that
  // error (a hundredth of it at most, and half the side margin), not the
  // hundredth of a tolerance it misses by far (30 bits a coordinate at 3 mm
  // for 3 000 km at 0.3 m).
  const Encoded over = encodeRoot(flat, 5);
  ASSERT_GT(over.record.error, 10 * over.tolerance);
  EXPECT_GT(over.record.positionErrorBound, 2 * 0.5 * tiles::kEncodingShare * over.tolerance);
  EXPECT_LE(over.record.positionErrorBound, 0.5 * tiles::kEncodingShare * over.record.error);
  EXPECT_LE(over.record.positionErrorBound, tiles::maxQuantization(over.width, over.tolerance));
  EXPECT_LE(over.record.positionBits, 25);
}

TEST(TileQuantization, ASmallTileKeepsItsFineSteps) {
  // 600 m at 0.2 m (the root's zoom at 0.8 m): within half the share and
  // 1 cm, as before wide tiles were, and within the tolerance.
  const TinData ridge = albersGrid(
      21, 30, [](double x, double y) { return 1700 + 60 * std::exp(-std::pow(x - y, 2) / 4e4); });
  const Encoded small = encodeRoot(ridge, 0.2);
  EXPECT_LE(small.record.positionErrorBound, 0.5 * tiles::kEncodingShare * small.tolerance);
  EXPECT_LE(small.record.positionErrorBound, 0.01);
  EXPECT_GE(small.record.positionErrorBound, 0.0005);
  EXPECT_LE(small.record.error, small.tolerance);
}

TEST(WideArea, ChordSagIsPlannedAsTheProjectionBendsIt) {
  // A UTM zone bends its lines less than the sphere of the smallest radius
  // allows for: the sphere's radius, as before.
  const ProjGeoReference utm("EPSG:32619", "");
  EXPECT_EQ(tiles::chordSagRadius(utm, {259000, 4873000, 373000, 4987000}),
            tiles::kEarthRadiusOfCurvature);
  EXPECT_EQ(tiles::chordSagRadius(utm, {100000, 4000000, 900000, 4800000}),
            tiles::kEarthRadiusOfCurvature);
  // CONUS Albers across 3 000 km, far from its centre: less.
  const ProjGeoReference albers("EPSG:5070", "");
  const double r = tiles::chordSagRadius(albers, {-2000000, 300000, 1000000, 3300000});
  EXPECT_LT(r, 0.9 * tiles::kEarthRadiusOfCurvature);
  EXPECT_GT(r, 0.5 * tiles::kEarthRadiusOfCurvature);
}

TEST(WideArea, AStretchingProjectionPlansTheSagItsChordsHave) {
  // World Mercator draws the ground at 75°N about 3.9 times its size. A
  // segment's chord sags about 1/15 of what the sphere says for its length,
  // but an east–west segment is a parallel, which also bends sideways on the
  // ground (tan φ / R): its middle lies about 1/3.9 as far from the chord as
  // the sphere says, and that is what a tile declares (shipped_error.hpp).
  const ProjGeoReference mercator("EPSG:3395", "");
  const double r = tiles::chordSagRadius(mercator, {0, 12800000, 400000, 13200000});
  EXPECT_GT(r, 2.5 * tiles::kEarthRadiusOfCurvature);
  EXPECT_LT(r, 4 * tiles::kEarthRadiusOfCurvature);
  // 400 km of it (about 100 km of ground) in hills, at 1 m: every tile
  // measured as shipped is within its tolerance, with fewer triangles than
  // the sphere's radius asks for.
  const TinData hills = projectedGrid("EPSG:3395", 0, 12800000, 81, 5000, [](double x, double y) {
    return 300 + 60 * std::sin(x / 1e5) * std::cos(y / 8e4);
  });
  const ProjGeoReference geo(hills.crs, "");
  tiles::ContentOptions content;
  content.geo = &geo;
  std::size_t triangles[2] = {0, 0};
  for (const bool stretches : {true, false}) {
    SCOPED_TRACE(stretches ? "planned as Mercator draws it" : "planned on the sphere");
    tiles::TilerOptions options;
    options.tolerance = 1;
    options.maxTriangles = 32768;
    options.threads = 1;
    options.maxZoom = 2;
    if (stretches) options.geo = &geo;
    const tiles::Tiler tiler(hills, options);
    for (int z = 0; z <= 1; ++z) {
      for (std::uint32_t y = 0; y < (1U << z); ++y) {
        for (std::uint32_t x = 0; x < (1U << z); ++x) {
          const tiles::TileSurface s = tiler.buildTile({z, x, y});
          if (s.empty()) continue;
          const auto c = tiles::encodeTile(s, tiles::skirtDepth(tiler, s.id, s.error), content);
          EXPECT_LE(c.record.error, s.tolerance) << s.id.name();
          triangles[stretches ? 0 : 1] += s.triangles.size();
        }
      }
    }
  }
  EXPECT_LT(2 * triangles[0], triangles[1]) << triangles[0] << " against " << triangles[1];
}

TEST(WideArea, AStripsTilesTakeTheBendingOfTheGroundTheyCover) {
  // 3 000 km of CONUS Albers east to west, 90 km north to south: the
  // pyramid's square reaches 2 900 km north of the strip, where the
  // projection bends its lines more. A tile's triangles lie on the strip, so
  // its sag radius is measured over the part of its square the strip's box
  // covers; before, the root took the radius of ground 2 900 km away.
  const auto hill = [](double x, double y) {
    return 300 + 200 * std::sin(x / 3e5) * std::cos(y / 4e4);
  };
  const TinData strip = projectedGrid("EPSG:5070", -2000000, 300000, 101, 30000, hill, 4);
  const ProjGeoReference geo(strip.crs, "");
  tiles::TilerOptions options;
  options.tolerance = 20;
  options.maxTriangles = 4096;
  options.threads = 1;
  options.geo = &geo;
  const tiles::Tiler tiler(strip, options);
  const tiles::Rect square = tiler.geometry().bounds({});
  const tiles::Rect box = tiles::boundsOf(strip.vertices);
  ASSERT_GT(square.height(), 30 * box.height());
  const double overStrip = tiles::chordSagRadius(geo, box);
  const double overSquare = tiles::chordSagRadius(geo, square);
  EXPECT_GT(overStrip, 1.05 * overSquare) << overStrip << " against " << overSquare;
  EXPECT_EQ(tiler.sagRadius(square), overStrip);
  // A square beside the TIN's box (no terrain) keeps its own.
  const tiles::Rect north{square.x0, box.y1 + 1000, square.x1, square.y1};
  EXPECT_EQ(tiler.sagRadius(north), tiles::chordSagRadius(geo, north));
  // A Tiler of a shard's subtree, which holds only its part of the TIN (the
  // east half, which the projection bends less), takes the whole TIN's box
  // from the plan: the same radius.
  auto plan = std::make_shared<const tiles::TilerPlan>(tiler.plan());
  EXPECT_EQ(plan->extent.x0, box.x0);
  EXPECT_EQ(plan->extent.y1, box.y1);
  const TinData east = projectedGrid("EPSG:5070", -500000, 300000, 51, 30000, hill, 4);
  ASSERT_GT(tiles::chordSagRadius(geo, tiles::boundsOf(east.vertices)), 1.01 * overStrip);
  tiles::TilerOptions part = options;
  part.plan = plan;
  part.region = tiler.geometry().bounds({1, 1, 0});
  const tiles::Tiler shard(east, part);
  EXPECT_EQ(shard.sagRadius(square), overStrip);
  // The root, measured as shipped, is within its tolerance.
  tiles::ContentOptions content;
  content.geo = &geo;
  const tiles::TileSurface root = tiler.buildTile({});
  ASSERT_FALSE(root.empty());
  const auto c = tiles::encodeTile(root, tiles::skirtDepth(tiler, root.id, root.error), content);
  EXPECT_LE(c.record.error, root.tolerance);
}

TEST(WideArea, TilesOfABendingProjectionMeetTheirTolerance) {
  // The 3 000 km of hills at 200 m, 8 192 triangles a tile: the zoom-1 and
  // zoom-2 tiles, measured as shipped (chord sag and bending included), are
  // within their tolerance — with the sphere's radius they were not.
  const TinData hills = albersGrid(41, 75000, [](double x, double y) {
    return 500 + 800 * std::sin(x / 4e5) * std::cos(y / 3e5);
  });
  const ProjGeoReference geo(hills.crs, "");
  tiles::ContentOptions content;
  content.geo = &geo;
  for (const bool bends : {true, false}) {
    tiles::TilerOptions options;
    options.tolerance = 200;
    options.maxTriangles = 8192;
    options.threads = 1;
    if (bends) options.geo = &geo;
    const tiles::Tiler tiler(hills, options);
    std::size_t over = 0, tiles = 0;
    for (int z = 1; z <= 2; ++z) {
      for (std::uint32_t y = 0; y < (1U << z); ++y) {
        for (std::uint32_t x = 0; x < (1U << z); ++x) {
          const tiles::TileSurface s = tiler.buildTile({z, x, y});
          if (s.empty()) continue;
          const auto c = tiles::encodeTile(s, tiles::skirtDepth(tiler, s.id, s.error), content);
          ++tiles;
          if (c.record.error > s.tolerance) ++over;
        }
      }
    }
    SCOPED_TRACE(bends ? "planned as Albers bends" : "planned on the sphere");
    EXPECT_EQ(tiles, 20u);
    if (bends)
      EXPECT_EQ(over, 0u);
    else
      EXPECT_GT(over, 0u);  // the test can tell
  }
}

}  // namespace
}  // namespace tinsmith::ingest
