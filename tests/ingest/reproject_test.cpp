// filters.reproject: known coordinates computed independently with
// GeographicLib, axis order, round trips, and layers without a CRS.
#include "ingest/filters/reproject.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/TransverseMercator.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <fstream>

#include "core/base/error.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/pipeline/load_layers.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

IngestedLayer pointLayer(const std::string& crs, std::vector<Point3> points) {
  IngestedLayer layer;
  layer.config.name = "test";
  layer.config.path = "test.csv";
  layer.kind = FeatureKind::SpotHeight;
  layer.crs = crs;
  layer.sourceCrs = crs;
  layer.points = std::move(points);
  for (std::size_t i = 0; i < layer.points.size(); ++i)
    layer.pointIds.push_back(static_cast<std::int64_t>(i + 1));
  return layer;
}

TEST(Reproject, Wgs84ToUtm12MatchesGeographicLib) {
  // Red Butte Canyon, and a point near the zone's edge.
  const std::vector<Point3> lonLat{{-111.8075, 40.7801, 1650.0}, {-113.9, 38.2, 0.0}};
  auto layer = pointLayer("EPSG:4326", lonLat);
  reprojectLayer(layer, "EPSG:32612");
  EXPECT_EQ(layer.crs, "EPSG:32612");
  for (std::size_t i = 0; i < lonLat.size(); ++i) {
    int zone = 0;
    bool north = false;
    double x = 0, y = 0;
    GeographicLib::UTMUPS::Forward(lonLat[i].y, lonLat[i].x, zone, north, x, y, 12);
    EXPECT_EQ(zone, 12);
    EXPECT_NEAR(layer.points[i].x, x, 1e-3) << i;
    EXPECT_NEAR(layer.points[i].y, y, 1e-3) << i;
    EXPECT_EQ(layer.points[i].z, lonLat[i].z);  // heights untouched
  }
}

TEST(Reproject, RoundTripUtmToGeographicAndBack) {
  const std::vector<Point3> utm{{431556.91048414, 4514331.82461309, 1650},
                                {440000.125, 4520000.5, 2000}};
  auto layer = pointLayer("EPSG:32612", utm);
  reprojectLayer(layer, "EPSG:4326");
  EXPECT_NEAR(layer.points[0].x, -111.8, 0.1);  // lon first: traditional GIS order
  EXPECT_NEAR(layer.points[0].y, 40.77, 0.1);
  reprojectLayer(layer, "EPSG:32612");
  for (std::size_t i = 0; i < utm.size(); ++i) {
    EXPECT_NEAR(layer.points[i].x, utm[i].x, 1e-6);
    EXPECT_NEAR(layer.points[i].y, utm[i].y, 1e-6);
  }
}

TEST(Reproject, NorthingFirstCrsKeepsEastingInX) {
  // NZTM Chatham Islands 2000 (EPSG:3793) is officially northing, easting;
  // x must still come out as the easting. Transverse Mercator on GRS80,
  // lat0 0, lon0 -176.5, k0 1, false easting 3 500 000, northing 10 000 000.
  const double lon = -176.35, lat = -44.25;
  auto layer = pointLayer("EPSG:4326", {{lon, lat, 0.0}});
  // The lines path too.
  IngestedFeature f;
  f.vertices = {{lon, lat, 5.0}, {lon + 0.01, lat, 5.0}};
  layer.features.push_back(f);
  reprojectLayer(layer, "EPSG:3793");
  const GeographicLib::TransverseMercator tm(GeographicLib::Constants::GRS80_a(),
                                             1.0 / 298.257222101, 1.0);  // GRS80 flattening
  double x = 0, y = 0;
  tm.Forward(-176.5, lat, lon, x, y);
  EXPECT_NEAR(layer.points[0].x, 3500000.0 + x, 1e-3);
  EXPECT_NEAR(layer.points[0].y, 10000000.0 + y, 1e-3);
  EXPECT_NEAR(layer.features[0].vertices[0].x, layer.points[0].x, 1e-9);
  EXPECT_GT(layer.features[0].vertices[1].x, layer.features[0].vertices[0].x);
}

TEST(Reproject, SameCrsIsUntouched) {
  const std::vector<Point3> utm{{431556.91048414, 4514331.82461309, 1650}};
  auto layer = pointLayer("EPSG:26912", utm);
  reprojectLayer(layer, "EPSG:26912");
  EXPECT_EQ(layer.points[0], utm[0]);
}

TEST(Reproject, LayerWithoutCrsIsAnError) {
  auto layer = pointLayer("", {{1, 2, 3}});
  layer.config.name = "survey";
  try {
    reprojectLayer(layer, "EPSG:26912");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    const std::string m = e.what();
    EXPECT_NE(m.find("survey"), std::string::npos) << m;
    EXPECT_NE(m.find("has no CRS"), std::string::npos) << m;
    EXPECT_NE(m.find("crs ="), std::string::npos) << m;
  }
}

TEST(Reproject, PointOutsideTheDomainNamesTheFeature) {
  auto layer = pointLayer("EPSG:4326", {{-111.8, 40.7, 0}, {10.0, 95.0, 0}});  // latitude 95
  try {
    reprojectLayer(layer, "EPSG:32612");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.where().feature, 2) << e.what();
  }
}

TEST(Reproject, ConfigWithCsvWithoutCrsFailsAtLoad) {
  const auto dir = test::scratchDir("reproject_no_crs");
  std::ofstream(dir / "pts.csv") << "x,y,z\n431000,4514000,1600\n";
  std::ofstream(dir / "p.toml")
      << "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\nkind = \"points\"\n";
  const auto config = loadProjectConfig(dir / "p.toml");
  try {
    loadLayers(config);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pts.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("has no CRS"), std::string::npos) << e.what();
  }
}

TEST(Reproject, SrtmToUtm19) {
  LayerConfig config;
  config.path = std::filesystem::path(TINSMITH_SHARED_DATA) / "srtm/N44W072.hgt";
  config.kind = LayerKind::Dem;
  config.name = "srtm";
  auto layer = readLayer(config);
  const auto first = layer.points.front();
  reprojectLayer(layer, "EPSG:32619");
  int zone = 0;
  bool north = false;
  double x = 0, y = 0;
  GeographicLib::UTMUPS::Forward(first.y, first.x, zone, north, x, y, 19);
  EXPECT_NEAR(layer.points.front().x, x, 1e-3);
  EXPECT_NEAR(layer.points.front().y, y, 1e-3);
}

}  // namespace
}  // namespace tinsmith::ingest
