// A shard's tiles from its part of the TIN: a Tiler given the whole TIN's
// plan (through the plan file) and only the part of the .tin around its
// square (readTinFilePart: the vertices only half its width around it) builds
// the tiles the whole TIN gives, bit for bit — on a TIN with a river, a hole
// whose edge crosses tile sides and corners off the TIN, and sparse triangles
// that the fit data sample.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <tuple>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/tiles/tiler.hpp"
#include "ingest/tiles/tiling_plan.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;

double ground(double x, double y) {
  return 200 + 40 * std::sin(x / 170) * std::cos(y / 230) + 0.02 * x;
}

/// 2 km × 1.6 km at UTM-sized coordinates: jittered points 40 m apart, none
/// in a 600 m gap (its triangles are sampled), a river across, and the
/// triangles of a disc dropped (a hole whose edge crosses tile sides).
TinData holedTin() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-9, 9);
  const double x0 = 620000, y0 = 4710000;
  std::vector<Point3> points;
  for (int j = 0; j <= 40; ++j) {
    for (int i = 0; i <= 50; ++i) {
      const double x = i * 40.0 + (i > 0 && i < 50 ? jitter(rng) : 0);
      const double y = j * 40.0 + (j > 0 && j < 40 ? jitter(rng) : 0);
      if (x > 1200 && x < 1800 && y > 200 && y < 800 && i % 15 != 0) continue;
      points.push_back({x0 + x, y0 + y, ground(x, y)});
    }
  }
  cdt.insertPoints(points, spots);
  std::vector<Point3> line;
  for (int k = 0; k <= 60; ++k) {
    const double x = 15 + k * 33.0, y = 1500 - k * 21.0 + 25 * std::sin(k / 3.0);
    line.push_back({x0 + x, y0 + y, ground(x, y) - 3 - 0.05 * k});
  }
  cdt.insertConstraint(line, river);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  std::vector<std::array<std::uint32_t, 3>> kept;
  for (const auto& t : tin.triangles) {
    double cx = 0, cy = 0;
    for (auto v : t) cx += tin.vertices[v].x / 3 - x0 / 3, cy += tin.vertices[v].y / 3 - y0 / 3;
    if (std::hypot(cx - 500, cy - 500) > 230) kept.push_back(t);
  }
  tin.triangles = kept;
  return tin;
}

/// A regular 10 m grid over 1 280 m × 1 280 m at UTM-sized coordinates, so
/// that its rows and columns lie on every tile side to zoom 7 and each cell's
/// four corners are cocircular, made to break the shard sides: a flat
/// plateau (z 500) west of a cliff 80 m high and 2 cm wide on the zoom-1 side
/// x = 640, a river along the zoom-1 side y = 640 and on across the cliff,
/// a road from corner to corner through the centre where the four zoom-1
/// tiles meet (it crosses the river there), a flat lake shore astride a
/// zoom-2 side, and one-vertex pits 30 m deep on a zoom-2 corner and 5 mm
/// inside a zoom-2 side (within the side margin: out of reach).
TinData sideBreakingTin() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  const double x0 = 430000, y0 = 4515000;
  auto ground = [](double x, double y) {
    return x <= 640 ? 500.0 : 420 - 0.01 * (x - 640) + 4 * std::sin(y / 90);
  };
  std::vector<Point3> points;
  for (int j = 0; j <= 128; ++j) {
    for (int i = 0; i <= 128; ++i) {
      const double x = i * 10.0, y = j * 10.0;
      const bool pit = i == 32 && j == 96;  // on a zoom-2 corner
      points.push_back({x0 + x, y0 + y, pit ? 470 : ground(x, y)});
    }
    // The cliff's foot, 2 cm east of its top on the side.
    points.push_back({x0 + 640.02, y0 + j * 10.0, ground(640.02, j * 10.0)});
  }
  points.push_back({x0 + 960.005, y0 + 335, 390});  // a pit 5 mm inside a zoom-2 side
  cdt.insertPoints(points, spots);
  std::vector<Point3> river;
  for (int k = 0; k <= 64; ++k) {
    const double x = 20.0 * k;
    river.push_back({x0 + x, y0 + 640, ground(x, 640) - 3 - 0.02 * k});
  }
  cdt.insertConstraint(river, cdt.addFeature(FeatureKind::River, "river"));
  std::vector<Point3> road;
  for (int k = 0; k <= 32; ++k) {
    const double t = 5 + 1270.0 * k / 32;
    road.push_back({x0 + t, y0 + t, ground(t, t) + 1});
  }
  cdt.insertConstraint(road, cdt.addFeature(FeatureKind::Road, "road"));
  std::vector<Point3> shore;
  for (int k = 0; k < 24; ++k) {
    const double a = 2 * std::numbers::pi * k / 24;
    shore.push_back({x0 + 960 + 70 * std::cos(a), y0 + 1000 + 50 * std::sin(a), 412});
  }
  cdt.insertConstraint(shore, cdt.addFeature(FeatureKind::Lake, "lake"), true);
  cdt.finalize();
  return cdt.toTinData();
}

void expectSameTile(const tiles::TileSurface& a, const tiles::TileSurface& b) {
  SCOPED_TRACE(a.id.name());
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.flags, b.flags);
  EXPECT_EQ(a.heldEdges, b.heldEdges);
  EXPECT_EQ(a.riverEdges, b.riverEdges);
  EXPECT_EQ(a.outOfReach, b.outOfReach);
  EXPECT_EQ(a.error, b.error);
  EXPECT_EQ(a.triangleErrors, b.triangleErrors);
}

struct PartComparison {
  std::size_t compared = 0;       ///< tiles built both ways
  std::size_t offTinCorners = 0;  ///< corners of tiles with terrain in no triangle
  std::size_t outOfReach = 0;     ///< tiles with triangles the refiner could not bring in
  int finestZoom = 0;
};

/// Writes `whole` in blocks of 128 records, plans it with the corners off the
/// TIN to `cornerZoom`, and builds every tile of zooms `shardZoom` to the
/// finest + 1 twice: from the whole TIN, and from the part of the file a
/// subtree shard at `shardZoom` reads with the plan read back — expecting
/// the same tiles, bit for bit.
PartComparison expectPartsBuildTheWholeTinsTiles(const std::string& name, const TinData& whole,
                                                 const tiles::TilerOptions& options, int shardZoom,
                                                 int cornerZoom) {
  const fs::path dir = fs::path(testing::TempDir()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Blocks of 128 records: a subtree's part reads some of them, not all.
  const std::string bytes = encodeTin(whole, 128);
  std::ofstream(dir / "site.tin", std::ios::binary) << bytes;

  PartComparison result;
  const tiles::Tiler wholeTiler(whole, options);
  result.finestZoom = wholeTiler.finestZoom();
  writeTilingPlan(dir / "tiler.plan", makeTilingPlan(whole, options, cornerZoom));
  const auto read = std::make_shared<const TilingPlan>(readTilingPlan(dir / "tiler.plan"));
  EXPECT_EQ(read->tiler.cornerZoom, cornerZoom);
  EXPECT_EQ(read->tiler.zoomLines.size(), static_cast<std::size_t>(wholeTiler.finestZoom()) + 1);
  EXPECT_NO_THROW(requirePlannedOptions(*read, options, "tiler.plan"));

  const tiles::TinIndex wholeIndex(whole);
  const std::uint32_t shards = 1U << shardZoom;
  for (std::uint32_t y = 0; y < shards; ++y) {
    for (std::uint32_t x = 0; x < shards; ++x) {
      const tiles::TileId subtree{shardZoom, x, y};
      SCOPED_TRACE("subtree " + subtree.name());
      const tiles::Rect square = read->tiler.geometry.bounds(subtree);
      const TinPart part = readTinFilePart(dir / "site.tin", tiles::tilerReadRegion(square),
                                           tiles::tilerVertexRegion(read->tiler, square));
      EXPECT_EQ(part.fileCrc, crc32(bytes));
      EXPECT_EQ(part.triangles, whole.triangles.size());
      EXPECT_EQ(part.vertices, whole.vertices.size());
      EXPECT_LT(part.tin.vertices.size(), whole.vertices.size());
      EXPECT_LT(part.tin.triangles.size(), whole.triangles.size());
      EXPECT_LT(part.bytesRead, bytes.size());
      tiles::TilerOptions partOptions = options;
      partOptions.plan = std::shared_ptr<const tiles::TilerPlan>(read, &read->tiler);
      partOptions.region = square;
      const tiles::Tiler partTiler(part.tin, partOptions);
      EXPECT_EQ(partTiler.geometry().size(), wholeTiler.geometry().size());
      EXPECT_EQ(partTiler.finestZoom(), wholeTiler.finestZoom());
      for (int z = shardZoom; z <= wholeTiler.finestZoom() + 1; ++z) {
        const int dz = z - shardZoom;
        for (std::uint32_t j = 0; j < (1U << dz); ++j) {
          for (std::uint32_t i = 0; i < (1U << dz); ++i) {
            const tiles::TileId id{z, (x << dz) + i, (y << dz) + j};
            const tiles::TileSurface a = wholeTiler.buildTile(id);
            expectSameTile(a, partTiler.buildTile(id));
            ++result.compared;
            if (a.empty()) continue;
            if (std::count(a.outOfReach.begin(), a.outOfReach.end(), 1) > 0) ++result.outOfReach;
            const tiles::Rect r = read->tiler.geometry.bounds(id);
            for (const Point2 corner :
                 {Point2{r.x0, r.y0}, Point2{r.x1, r.y0}, Point2{r.x0, r.y1}, Point2{r.x1, r.y1}})
              if (!wholeIndex.z(corner)) ++result.offTinCorners;
          }
        }
      }
    }
  }
  return result;
}

TEST(TilePart, AShardsPartOfTheTinWithThePlanBuildsTheWholeTinsTilesBitForBit) {
  tiles::TilerOptions options;
  options.tolerance = 0.1;
  options.maxTriangles = 512;
  options.threads = 1;
  // The corners off the TIN to zoom 3 in the plan: a part holds the
  // vertices only half a subtree's width around it (tilerVertexRegion).
  const PartComparison c =
      expectPartsBuildTheWholeTinsTiles("tile_part", holedTin(), options, 1, 3);
  EXPECT_GE(c.finestZoom, 2);
  EXPECT_GT(c.compared, 20u);
  EXPECT_GT(c.offTinCorners, 0u);  // the hole's tiles were among them

  const TilingPlan plan = makeTilingPlan(holedTin(), options, 3);
  EXPECT_FALSE(plan.tiler.offTinCorners.empty());
  tiles::TilerOptions other = options;
  other.tolerance = 1;
  EXPECT_THROW(requirePlannedOptions(plan, other, "tiler.plan"), Error);
}

// Terrain made to break the shards where they meet: every vertex row on a
// tile side, a cliff, a river and a road along and across the sides and
// corners, a flat plateau and lake, pits on a corner and within a side's
// margin — at shard zooms 1 and 2.
TEST(TilePart, SidesCornersCliffsAndPitsAreBuiltTheSameFromEveryPart) {
  const TinData whole = sideBreakingTin();
  tiles::TilerOptions options;
  options.tolerance = 0.5;
  options.maxTriangles = 512;
  options.threads = 1;
  for (const int shardZoom : {1, 2}) {
    SCOPED_TRACE("shard zoom " + std::to_string(shardZoom));
    const PartComparison c = expectPartsBuildTheWholeTinsTiles(
        "tile_part_sides_" + std::to_string(shardZoom), whole, options, shardZoom, 3);
    EXPECT_GE(c.finestZoom, shardZoom + 1);
    EXPECT_GT(c.compared, 40u);
    EXPECT_GT(c.outOfReach, 0u);  // the pit within the side margin
  }
}

TEST(TilePart, ThePlansCornersOffTheTinTakeTheNearestVertex) {
  const TinData whole = holedTin();
  tiles::TilerOptions options;
  options.tolerance = 0.1;
  options.maxTriangles = 512;
  options.threads = 1;
  const TilingPlan plan = makeTilingPlan(whole, options, 4);
  const tiles::TinIndex index(whole);
  const tiles::PyramidGeometry& g = plan.tiler.geometry;
  // Every corner of zooms 0 … 4 in no triangle and within a tile width of
  // the TIN's box, in order, with the z of the nearest vertex in the first
  // of the boxes, growing from 1/64 to 4 tile widths, that holds any (the
  // lowest index among equally near ones).
  const tiles::Rect box = tiles::boundsOf(whole.vertices);
  std::vector<tiles::TilerPlan::OffTinCorner> expected;
  std::size_t far = 0;
  for (int z = 0; z <= 4; ++z) {
    const double width = std::ldexp(g.size(), -z);
    for (std::uint32_t row = 0; row <= (1U << z); ++row) {
      for (std::uint32_t column = 0; column <= (1U << z); ++column) {
        const Point2 p{g.lineX(z, column), g.lineY(z, row)};
        if (index.z(p)) continue;
        if (p.x < box.x0 - width || p.x > box.x1 + width || p.y < box.y0 - width ||
            p.y > box.y1 + width) {
          ++far;
          continue;
        }
        double value = 0;
        for (double r = width / 64; r <= 4 * width; r *= 2) {
          double best = HUGE_VAL;
          for (const Point3& v : whole.vertices) {
            if (std::abs(v.x - p.x) > r || std::abs(v.y - p.y) > r) continue;
            const double d = std::hypot(v.x - p.x, v.y - p.y);
            if (d < best) best = d, value = v.z;
          }
          if (best < HUGE_VAL) break;
        }
        expected.push_back({z, row, column, value});
      }
    }
  }
  ASSERT_EQ(plan.tiler.offTinCorners.size(), expected.size());
  EXPECT_GT(expected.size(), 20u);  // the hole's and the square's beyond the TIN
  std::size_t nearHole = 0;
  for (std::size_t k = 0; k < expected.size(); ++k) {
    const auto& a = plan.tiler.offTinCorners[k];
    const auto& b = expected[k];
    EXPECT_EQ(std::tuple(a.zoom, a.row, a.column, a.z), std::tuple(b.zoom, b.row, b.column, b.z));
    if (b.z != 0) ++nearHole;
  }
  EXPECT_GT(nearHole, 0u);
  EXPECT_GT(far, 0u);  // the square reaches beyond the TIN's box
  // Past kMaxCornerZoom the plan is refused, not made huge.
  EXPECT_THROW((void)makeTilingPlan(whole, options, tiles::kMaxCornerZoom + 1), Error);
}

TEST(TilePart, ADamagedFileIsRefusedWhenReadInPart) {
  const fs::path dir = fs::path(testing::TempDir()) / "tile_part_damaged";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const TinData whole = holedTin();
  std::string bytes = encodeTin(whole);
  bytes[bytes.size() - 100] ^= 0x10;  // in the block index
  std::ofstream(dir / "damaged.tin", std::ios::binary) << bytes;
  const tiles::Rect everything{-1e9, -1e9, 1e9, 1e9};
  EXPECT_THROW((void)readTinFilePart(dir / "damaged.tin", everything, everything), Error);
  EXPECT_THROW((void)readTinFilePart(dir / "missing.tin", everything, everything), Error);
  TilingPlan empty;
  empty.tiler.zoomLines.resize(1);  // finest zoom 0: one set of lines
  std::string plan = encodeTilingPlan(empty);
  EXPECT_NO_THROW((void)decodeTilingPlan(plan, "plan"));
  plan[20] ^= 1;
  EXPECT_THROW((void)decodeTilingPlan(plan, "plan"), Error);
}

}  // namespace
}  // namespace tinsmith::ingest
