// readers.ogr (and the layer dispatch): GeoJSON, GeoPackage and Shapefile made
// here with OGR, the real Red Butte and Chatham layers, and every bad input.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>

#include <cmath>
#include <fstream>
#include <set>

#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

const std::filesystem::path kData = TINSMITH_SHARED_DATA;

LayerConfig layerConfig(const std::filesystem::path& path, LayerKind kind,
                        const std::string& z = {}, const std::string& layer = {}) {
  LayerConfig c;
  c.path = path;
  c.kind = kind;
  c.zAttribute = z;
  c.layer = layer;
  c.name = path.filename().string();
  return c;
}

std::filesystem::path writeText(const std::filesystem::path& dir, const std::string& name,
                                const std::string& text) {
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no tinsmith::Error thrown";
  return {};
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A vector file made with OGR: `driver` "GPKG" or "ESRI Shapefile"; features
// given as WKT with an 'elev' Real and a 'label' String attribute.
struct FixtureFeature {
  std::string wkt;
  std::optional<double> elev;
  std::string label = "x";
};

std::filesystem::path makeVectorFile(const std::filesystem::path& path, const char* driverName,
                                     const char* layerName, OGRwkbGeometryType type,
                                     const std::vector<FixtureFeature>& features,
                                     int epsg = 26912) {
  ensureGdalReady();
  auto* driver = GetGDALDriverManager()->GetDriverByName(driverName);
  EXPECT_NE(driver, nullptr);
  std::unique_ptr<GDALDataset> ds(
      driver->Create(path.string().c_str(), 0, 0, 0, GDT_Unknown, nullptr));
  EXPECT_NE(ds, nullptr);
  OGRSpatialReference srs;
  if (epsg) srs.importFromEPSG(epsg);
  auto* layer = ds->CreateLayer(layerName, epsg ? &srs : nullptr, type, nullptr);
  OGRFieldDefn elev("elev", OFTReal);
  layer->CreateField(&elev);
  OGRFieldDefn label("label", OFTString);
  layer->CreateField(&label);
  for (const auto& f : features) {
    OGRFeature feature(layer->GetLayerDefn());
    OGRGeometry* g = nullptr;
    EXPECT_EQ(OGRGeometryFactory::createFromWkt(f.wkt.c_str(), nullptr, &g), OGRERR_NONE) << f.wkt;
    feature.SetGeometryDirectly(g);
    if (f.elev) feature.SetField("elev", *f.elev);
    feature.SetField("label", f.label.c_str());
    EXPECT_EQ(layer->CreateFeature(&feature), OGRERR_NONE);
  }
  return path;
}

TEST(OgrReader, GeoJsonPointsWithZAttribute) {
  const auto dir = test::scratchDir("ogr_geojson_points");
  const auto path = writeText(dir, "pts.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","id":7,"properties":{"h":101.5},"geometry":{"type":"Point","coordinates":[1,2]}},
    {"type":"Feature","id":8,"properties":{"h":"102"},"geometry":{"type":"MultiPoint","coordinates":[[3,4],[5,6]]}},
    {"type":"Feature","id":9,"properties":{"h":1},"geometry":null}]})");
  const auto layer = readLayer(layerConfig(path, LayerKind::Points, "h"));
  ASSERT_EQ(layer.points.size(), 3u);
  EXPECT_EQ(layer.points[0], (Point3{1, 2, 101.5}));
  EXPECT_EQ(layer.points[2], (Point3{5, 6, 102}));
  EXPECT_EQ(layer.pointIds[0], 7);
  EXPECT_EQ(layer.pointIds[2], 8);
  EXPECT_EQ(layer.nullGeometriesSkipped, 1u);
  EXPECT_EQ(layer.kind, FeatureKind::SpotHeight);
  EXPECT_EQ(layer.sourceCrs, "EPSG:4326");  // GeoJSON's default
}

TEST(OgrReader, GeoJson3DLinesPartsAndRings) {
  const auto dir = test::scratchDir("ogr_geojson_lines");
  const auto path = writeText(dir, "lines.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","id":1,"properties":{},"geometry":{"type":"LineString","coordinates":[[0,0,10],[1,0,10],[1,1,10]]}},
    {"type":"Feature","id":2,"properties":{},"geometry":{"type":"MultiLineString","coordinates":[[[0,5,20],[1,5,20]],[[0,6,20],[1,6,20],[1,7,20],[0,6,20]]]}},
    {"type":"Feature","id":3,"properties":{},"geometry":{"type":"Polygon","coordinates":[[[10,10,30],[20,10,30],[20,20,30],[10,10,30]]]}}]})");
  const auto layer = readLayer(layerConfig(path, LayerKind::Contours));
  ASSERT_EQ(layer.features.size(), 4u);
  EXPECT_TRUE(layer.hasZ);
  EXPECT_EQ(layer.features[0].vertices.size(), 3u);
  EXPECT_EQ(layer.features[0].vertices[2], (Point3{1, 1, 10}));
  EXPECT_FALSE(layer.features[0].closed);
  EXPECT_EQ(layer.features[1].fid, 2);
  EXPECT_EQ(layer.features[1].part, 0);
  EXPECT_EQ(layer.features[2].part, 1);
  EXPECT_TRUE(layer.features[2].closed);  // closing vertex dropped
  EXPECT_EQ(layer.features[2].vertices.size(), 3u);
  EXPECT_TRUE(layer.features[3].closed);  // a polygon ring taken as a closed contour
  EXPECT_EQ(layer.features[3].vertices[0].z, 30);
}

TEST(OgrReader, PolygonsWithHolesForAreaKinds) {
  const auto dir = test::scratchDir("ogr_polygons");
  const auto path = writeText(dir, "lake.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","id":4,"properties":{"level":12.5},"geometry":{"type":"MultiPolygon","coordinates":[
      [[[0,0],[10,0],[10,10],[0,10],[0,0]],[[2,2],[3,2],[3,3],[2,2]]],
      [[[20,0],[30,0],[30,10],[20,0]]]]}}]})");
  auto layer = readLayer(layerConfig(path, LayerKind::Lake));
  ASSERT_EQ(layer.features.size(), 3u);
  EXPECT_FALSE(layer.hasZ);  // 2D and no z: to be draped
  EXPECT_TRUE(std::isnan(layer.features[0].vertices[0].z));
  EXPECT_EQ(layer.features[0].ring, 0);
  EXPECT_EQ(layer.features[1].ring, 1);
  EXPECT_EQ(layer.features[1].part, 0);
  EXPECT_EQ(layer.features[2].part, 1);
  EXPECT_EQ(layer.features[0].vertices.size(), 4u);

  auto fixed = layerConfig(path, LayerKind::Lake, "level");
  layer = readLayer(fixed);
  EXPECT_TRUE(layer.hasZ);
  EXPECT_EQ(layer.features[2].vertices[1].z, 12.5);

  fixed.zAttribute.clear();
  fixed.zValue = 3.0;
  layer = readLayer(fixed);
  EXPECT_EQ(layer.features[1].vertices[0].z, 3.0);
}

TEST(OgrReader, GeoPackageMadeWithOgr) {
  const auto dir = test::scratchDir("ogr_gpkg");
  const auto path = makeVectorFile(
      dir / "c.gpkg", "GPKG", "contours", wkbLineString,
      {{"LINESTRING (0 0, 10 0, 20 5)", 100.0}, {"LINESTRING (0 10, 20 10)", 120.0}});
  auto config = layerConfig(path, LayerKind::Contours, "elev", "contours");
  const auto layer = readLayer(config);
  ASSERT_EQ(layer.features.size(), 2u);
  EXPECT_EQ(layer.features[0].fid, 1);
  EXPECT_EQ(layer.features[1].fid, 2);
  EXPECT_EQ(layer.features[1].vertices[1], (Point3{20, 10, 120}));
  EXPECT_EQ(layer.sourceCrs, "EPSG:26912");

  config.layer = "nope";
  const auto message = errorOf([&] { readLayer(config); });
  EXPECT_TRUE(contains(message, "has no layer 'nope'")) << message;
  EXPECT_TRUE(contains(message, "'contours'")) << message;
}

TEST(OgrReader, ShapefileMadeWithOgr) {
  const auto dir = test::scratchDir("ogr_shp");
  const auto path = makeVectorFile(dir / "spots.shp", "ESRI Shapefile", "spots", wkbPoint,
                                   {{"POINT (1 2)", 5.0}, {"POINT (3 4)", 6.0}}, 32619);
  const auto layer = readLayer(layerConfig(path, LayerKind::Points, "elev"));
  ASSERT_EQ(layer.points.size(), 2u);
  EXPECT_EQ(layer.points[1], (Point3{3, 4, 6}));
  EXPECT_EQ(layer.pointIds[0], 0);  // shapefile FIDs start at 0
  EXPECT_EQ(layer.sourceCrs, "EPSG:32619");
}

TEST(OgrReader, BadInput) {
  const auto dir = test::scratchDir("ogr_bad");
  // Missing and unreadable files.
  auto m = errorOf([&] { readLayer(layerConfig(dir / "gone.gpkg", LayerKind::Contours, "elev")); });
  EXPECT_TRUE(contains(m, "gone.gpkg") && contains(m, "not found")) << m;
  const auto garbage = writeText(dir, "garbage.geojson", "{ this is not json");
  m = errorOf([&] { readLayer(layerConfig(garbage, LayerKind::Contours, "elev")); });
  EXPECT_TRUE(contains(m, "garbage.geojson") && contains(m, "cannot open")) << m;

  // A layer without the z attribute names the numeric attributes there are.
  const auto gpkg =
      makeVectorFile(dir / "c.gpkg", "GPKG", "contours", wkbLineString,
                     {{"LINESTRING (0 0, 10 0)", 100.0}, {"LINESTRING (0 5, 10 5)", std::nullopt}});
  m = errorOf([&] { readLayer(layerConfig(gpkg, LayerKind::Contours, "height")); });
  EXPECT_TRUE(contains(m, "has no attribute 'height'") && contains(m, "elev")) << m;

  // An empty z on feature 2.
  m = errorOf([&] { readLayer(layerConfig(gpkg, LayerKind::Contours, "elev")); });
  EXPECT_TRUE(contains(m, "feature 2") && contains(m, "'elev' is empty")) << m;

  // A non-numeric z, and NaN given as text.
  const auto text = makeVectorFile(
      dir / "t.gpkg", "GPKG", "t", wkbLineString,
      {{"LINESTRING (0 0, 10 0)", 1.0, "12.5"}, {"LINESTRING (0 5, 10 5)", 1.0, "n/a"}});
  m = errorOf([&] { readLayer(layerConfig(text, LayerKind::Contours, "label")); });
  EXPECT_TRUE(contains(m, "feature 2") && contains(m, "not numeric ('n/a')")) << m;
  const auto nan = makeVectorFile(dir / "n.gpkg", "GPKG", "n", wkbLineString,
                                  {{"LINESTRING (0 0, 10 0)", 1.0, "NaN"}});
  m = errorOf([&] { readLayer(layerConfig(nan, LayerKind::Contours, "label")); });
  EXPECT_TRUE(contains(m, "feature 1") && contains(m, "not finite")) << m;

  // 2D contours with no z attribute.
  const auto flat = writeText(dir, "flat.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","id":3,"properties":{},"geometry":{"type":"LineString","coordinates":[[0,0],[1,1]]}}]})");
  m = errorOf([&] { readLayer(layerConfig(flat, LayerKind::Contours)); });
  EXPECT_TRUE(contains(m, "feature 3") && contains(m, "2D geometry")) << m;

  // A polygon kind given to a point file (GeoJSON and CSV).
  const auto points = writeText(dir, "p.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","id":0,"properties":{"h":1},"geometry":{"type":"Point","coordinates":[0,0]}}]})");
  m = errorOf([&] { readLayer(layerConfig(points, LayerKind::Lake, "h")); });
  EXPECT_TRUE(contains(m, "feature 0") && contains(m, "is a POINT") &&
              contains(m, "kind = \"lake\""))
      << m;
  const auto csv = writeText(dir, "p.csv", "x,y,z\n1,2,3\n");
  m = errorOf([&] { readLayer(layerConfig(csv, LayerKind::Boundary)); });
  EXPECT_TRUE(contains(m, "p.csv") && contains(m, "kind = \"boundary\"")) << m;
  // Lines given as points, and an open line as an area.
  m = errorOf([&] { readLayer(layerConfig(gpkg, LayerKind::Points, "elev")); });
  EXPECT_TRUE(contains(m, "LINESTRING") && contains(m, "kind = \"contours\"")) << m;
  m = errorOf([&] { readLayer(layerConfig(flat, LayerKind::Boundary)); });
  EXPECT_TRUE(contains(m, "open line")) << m;

  // An empty layer.
  const auto empty =
      writeText(dir, "empty.geojson", R"({"type":"FeatureCollection","features":[]})");
  m = errorOf([&] { readLayer(layerConfig(empty, LayerKind::Road)); });
  EXPECT_TRUE(contains(m, "empty.geojson") && contains(m, "holds no features")) << m;

  // A raster given a vector kind.
  m = errorOf([&] { readLayer(layerConfig(kData / "red-butte/dem.tif", LayerKind::Points, "z")); });
  EXPECT_TRUE(contains(m, "kind = \"dem\"")) << m;
}

TEST(OgrReader, RedButteLayers) {
  const auto contours = readLayer(
      layerConfig(kData / "red-butte/contours.gpkg", LayerKind::Contours, "elev", "contours"));
  EXPECT_EQ(contours.sourceCrs, "EPSG:26912");
  std::set<std::int64_t> fids;
  for (const auto& f : contours.features) {
    fids.insert(f.fid);
    EXPECT_EQ(std::fmod(f.vertices[0].z, 20.0), 0.0);
    EXPECT_GE(f.vertices[0].z, 1580);
    EXPECT_LE(f.vertices[0].z, 2520);
  }
  EXPECT_EQ(fids.size(), 152u);

  const auto road = readLayer(layerConfig(kData / "red-butte/road.geojson", LayerKind::Road));
  EXPECT_EQ(road.features.size(), 1u);
  EXPECT_FALSE(road.hasZ);
  EXPECT_GT(road.features[0].vertices.size(), 10u);

  const auto streams =
      readLayer(layerConfig(kData / "red-butte/streams.geojson", LayerKind::River));
  EXPECT_EQ(streams.features.size(), 23u);

  const auto reservoir =
      readLayer(layerConfig(kData / "red-butte/reservoir.geojson", LayerKind::Lake));
  ASSERT_GE(reservoir.features.size(), 1u);
  EXPECT_TRUE(reservoir.features[0].closed);

  const auto boundary =
      readLayer(layerConfig(kData / "red-butte/boundary.geojson", LayerKind::Boundary));
  ASSERT_GE(boundary.features.size(), 1u);
  EXPECT_TRUE(boundary.features[0].closed);
  EXPECT_EQ(boundary.sourceCrs, "EPSG:26912");

  auto spots = layerConfig(kData / "red-butte/spot-heights.csv", LayerKind::Points, "elevation");
  spots.crs = "EPSG:26912";
  const auto spotLayer = readLayer(spots);
  EXPECT_EQ(spotLayer.points.size(), 400u);
  EXPECT_EQ(spotLayer.pointIds[0], 2);  // line 2, after the header
}

TEST(OgrReader, ChathamLayers) {
  const auto contours = readLayer(layerConfig(kData / "chatham/se-island-contours.gpkg",
                                              LayerKind::Contours, "elevation", "contours"));
  EXPECT_EQ(contours.sourceCrs, "EPSG:3793");
  EXPECT_GE(contours.features.size(), 18u);
  for (const auto& f : contours.features) {
    EXPECT_GE(f.vertices[0].z, 20);
    EXPECT_LE(f.vertices[0].z, 220);
  }
  const auto points = readLayer(
      layerConfig(kData / "chatham/se-island-height-pts.gpkg", LayerKind::Points, "elevation"));
  EXPECT_EQ(points.points.size(), 5u);

  auto coast =
      layerConfig(kData / "chatham/se-island-exterior.gpkg", LayerKind::Contours, "", "se_island");
  coast.zValue = 0.0;
  const auto rings = readLayer(coast);
  EXPECT_GE(rings.features.size(), 14u);
  for (const auto& f : rings.features) EXPECT_EQ(f.vertices[0].z, 0.0);
}

}  // namespace
}  // namespace tinsmith::ingest
