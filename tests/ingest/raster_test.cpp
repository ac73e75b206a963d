// readers.raster / writers.raster: GeoTIFF and EXR round trips with
// georeferencing and nodata, DEM layers as points, the real dem.tif and SRTM.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <limits>
#include <thread>

#include "core/base/error.hpp"
#include "ingest/export/raster_writer.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "ingest/readers/raster_reader.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

const std::filesystem::path kData = TINSMITH_SHARED_DATA;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

HeightGrid sampleGrid() {
  HeightGrid g;
  g.width = 5;
  g.height = 3;
  g.geotransform = {431000.5, 2.0, 0.0, 4514000.25, 0.0, -2.0};
  g.crs = "EPSG:26912";
  for (int i = 0; i < g.width * g.height; ++i)
    g.z.push_back(1600.0f + 0.25f * static_cast<float>(i));
  g.z[7] = kNaN;
  return g;
}

void expectSameGrid(const HeightGrid& a, const HeightGrid& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(a.geotransform[i], b.geotransform[i]) << i;
  ASSERT_EQ(a.z.size(), b.z.size());
  for (std::size_t i = 0; i < a.z.size(); ++i) {
    if (std::isnan(a.z[i])) {
      EXPECT_TRUE(std::isnan(b.z[i])) << i;
    } else {
      EXPECT_EQ(a.z[i], b.z[i]) << i;
    }
  }
}

TEST(RasterIo, GeoTiffRoundTrip) {
  const auto dir = test::scratchDir("raster_tif");
  const auto grid = sampleGrid();
  writeGeoTiff(grid, dir / "h.tif");
  EXPECT_EQ(test::filesIn(dir), 1u);  // no temp file left beside it
  const auto back = readHeightGrid(dir / "h.tif");
  expectSameGrid(grid, back);
  EXPECT_EQ(back.crs, "EPSG:26912");
}

TEST(RasterIo, ExrRoundTripKeepsGeoreferencing) {
  const auto dir = test::scratchDir("raster_exr");
  const auto grid = sampleGrid();
  writeExr(grid, dir / "h.exr");
  const auto back = readExr(dir / "h.exr");
  expectSameGrid(grid, back);
  EXPECT_EQ(back.crs, "EPSG:26912");
  // Through the generic entry point too, with a nodata override.
  RasterReadOptions options;
  options.nodata = 1600.0;
  const auto masked = readHeightGrid(dir / "h.exr", options);
  EXPECT_TRUE(std::isnan(masked.z[0]));
  EXPECT_EQ(masked.z[1], 1600.25f);
}

TEST(RasterIo, NodataBecomesNaNAndPointsSkipIt) {
  const auto dir = test::scratchDir("raster_nodata");
  auto grid = sampleGrid();
  grid.z[3] = -9999.0f;
  writeGeoTiff(grid, dir / "h.tif");
  RasterReadOptions options;
  options.nodata = -9999.0;
  const auto back = readHeightGrid(dir / "h.tif", options);
  EXPECT_TRUE(std::isnan(back.z[3]));

  std::vector<std::int64_t> ids;
  const auto points = gridToPoints(back, &ids);
  EXPECT_EQ(points.size(), 13u);  // 15 cells, two nodata
  // Cell (0, 0) centre: one half cell right and down of the corner.
  EXPECT_EQ(points[0], (Point3{431001.5, 4513999.25, 1600.0}));
  EXPECT_EQ(ids[3], 4);  // cells 3 (nodata) skipped
  const auto c = back.cellCentre(4, 2);
  EXPECT_EQ(points.back(), (Point3{c.x, c.y, 1603.5}));
}

TEST(RasterIo, DemLayer) {
  const auto dir = test::scratchDir("raster_layer");
  writeExr(sampleGrid(), dir / "h.exr");
  LayerConfig config;
  config.path = dir / "h.exr";
  config.kind = LayerKind::Dem;
  config.name = "h.exr";
  const auto layer = readLayer(config);
  EXPECT_EQ(layer.kind, FeatureKind::Raster);
  EXPECT_EQ(layer.points.size(), 14u);
  EXPECT_EQ(layer.sourceCrs, "EPSG:26912");
  EXPECT_TRUE(layer.features.empty());
}

TEST(RasterIo, Errors) {
  const auto dir = test::scratchDir("raster_errors");
  auto expectMessage = [](auto&& f, const std::string& part) {
    try {
      f();
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  expectMessage([&] { readHeightGrid(dir / "gone.tif"); }, "not found");
  std::ofstream(dir / "junk.tif") << "not a tiff";
  expectMessage([&] { readHeightGrid(dir / "junk.tif"); }, "cannot open as a raster");
  std::ofstream(dir / "junk.exr") << "not an exr";
  expectMessage([&] { readHeightGrid(dir / "junk.exr"); }, "junk.exr");
  writeGeoTiff(sampleGrid(), dir / "h.tif");
  RasterReadOptions band2;
  band2.band = 2;
  expectMessage([&] { readHeightGrid(dir / "h.tif", band2); }, "has no band 2");
  HeightGrid bad = sampleGrid();
  bad.z.pop_back();
  expectMessage([&] { writeExr(bad, dir / "bad.exr"); }, "malformed");
  expectMessage([&] { writeGeoTiff(sampleGrid(), dir / "no-such-dir" / "h.tif"); },
                "no-such-dir' does not exist");
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.exr"));
}

TEST(RasterIo, AFailedWriteLeavesNoTempFileAndNoPartialTarget) {
  const auto dir = test::scratchDir("raster_failed_write");
  auto bad = sampleGrid();
  bad.crs = "not a CRS";  // GDAL fails after the file is created
  EXPECT_THROW(writeGeoTiff(bad, dir / "h.tif"), Error);
  EXPECT_EQ(test::filesIn(dir), 0u);
  // Over an existing target: the old file stays, byte for byte.
  writeGeoTiff(sampleGrid(), dir / "h.tif");
  const std::string before = test::readFile(dir / "h.tif");
  EXPECT_THROW(writeGeoTiff(bad, dir / "h.tif"), Error);
  EXPECT_EQ(test::readFile(dir / "h.tif"), before);
  EXPECT_EQ(test::filesIn(dir), 1u);
  // A target that cannot be replaced (a folder): the finished temp file goes.
  std::filesystem::create_directories(dir / "taken.exr" / "inside");
  std::filesystem::create_directories(dir / "taken.tif" / "inside");
  EXPECT_THROW(writeExr(sampleGrid(), dir / "taken.exr"), Error);
  EXPECT_THROW(writeGeoTiff(sampleGrid(), dir / "taken.tif"), Error);
  EXPECT_EQ(test::filesIn(dir), 3u);
}

TEST(RasterIo, TwoWritersOfOneTargetDoNotCollide) {
  // Each writer has its own temp file, so the target is always one of the
  // two grids, whole — with one fixed temp name they wrote into one file.
  const auto dir = test::scratchDir("raster_two_writers");
  auto other = sampleGrid();
  for (auto& z : other.z) z += 100.0f;
  for (const bool exr : {false, true}) {
    const auto target = dir / (exr ? "h.exr" : "h.tif");
    std::atomic<int> failures{0};
    auto write = [&](const HeightGrid& grid) {
      for (int i = 0; i < 20; ++i) {
        try {
          exr ? writeExr(grid, target) : writeGeoTiff(grid, target);
        } catch (const Error&) {
          ++failures;
        }
      }
    };
    std::thread a(write, sampleGrid());
    std::thread b(write, other);
    a.join();
    b.join();
    EXPECT_EQ(failures, 0) << target;
    const auto back = readHeightGrid(target);
    expectSameGrid(back.z[0] == other.z[0] ? other : sampleGrid(), back);
  }
  EXPECT_EQ(test::filesIn(dir), 2u);
}

TEST(RasterIo, RedButteDem) {
  const auto grid = readHeightGrid(kData / "red-butte/dem.tif");
  EXPECT_EQ(grid.width, 260);
  EXPECT_EQ(grid.height, 268);
  EXPECT_EQ(grid.crs, "EPSG:26912");
  float lo = 1e9f, hi = -1e9f;
  for (const float v : grid.z) {
    if (std::isnan(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_GT(lo, 1570.0f);
  EXPECT_LT(hi, 2530.0f);
  EXPECT_GT(hi - lo, 800.0f);

  // Through EXR and back: identical cells and georeferencing.
  const auto dir = test::scratchDir("raster_red_butte");
  writeExr(grid, dir / "dem.exr");
  expectSameGrid(grid, readExr(dir / "dem.exr"));
}

TEST(RasterIo, StripsGiveTheWholeGridsPoints) {
  // The Red Butte DEM (nodata around its edges) in strips of one row, of a
  // few rows that do not divide its 268, and whole: gridToPoints's points.
  const auto path = kData / "red-butte/dem.tif";
  const auto whole = gridToPoints(readHeightGrid(path));
  ASSERT_GT(whole.size(), 30000u);
  for (const std::size_t cells : {std::size_t{1}, std::size_t{260 * 7}, std::size_t{1} << 30}) {
    std::vector<Point3> points;
    int strips = 0, next = 0;
    readHeightGridInStrips(path, {}, cells,
                           [&](const HeightGrid& frame, int first, std::span<const float> z) {
                             EXPECT_EQ(first, next);
                             EXPECT_TRUE(frame.z.empty());
                             next = first + static_cast<int>(z.size()) / frame.width;
                             ++strips;
                             const auto strip = stripToPoints(frame, first, z);
                             points.insert(points.end(), strip.begin(), strip.end());
                           });
    EXPECT_EQ(next, 268);
    EXPECT_EQ(strips, cells == 1 ? 268 : cells == 260 * 7 ? 39 : 1);
    EXPECT_EQ(points, whole) << cells << " cells a strip";
  }
}

TEST(RasterIo, SrtmHgt) {
  const auto grid = readHeightGrid(kData / "srtm/N44W072.hgt");
  EXPECT_EQ(grid.width, 1201);
  EXPECT_EQ(grid.height, 1201);
  EXPECT_EQ(grid.crs, "EPSG:4326");
  // Cell centres sit on the 3" lattice: the first one is 44+1 N, 72 W.
  const auto c = grid.cellCentre(0, 0);
  EXPECT_NEAR(c.x, -72.0, 1e-9);
  EXPECT_NEAR(c.y, 45.0, 1e-9);
  const auto points = gridToPoints(grid);
  EXPECT_GT(points.size(), 1400000u);
  double lo = 1e9, hi = -1e9;
  for (const auto& p : points) {
    lo = std::min(lo, p.z);
    hi = std::max(hi, p.z);
  }
  EXPECT_GE(lo, 100);
  EXPECT_LE(hi, 1910);
}

}  // namespace
}  // namespace tinsmith::ingest
