// filters.clean: every rule on small fixtures, strict mode, and whole real
// configs through loadLayers.
#include "ingest/filters/clean.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/base/error.hpp"
#include "ingest/pipeline/load_layers.hpp"

namespace tinsmith::ingest {
namespace {

IngestedLayer lineLayer(const std::string& name, FeatureKind kind,
                        std::vector<std::vector<Point3>> lines, bool closed = false) {
  IngestedLayer layer;
  layer.config.name = name;
  layer.config.path = name + ".gpkg";
  layer.kind = kind;
  std::int64_t fid = 1;
  for (auto& line : lines) {
    IngestedFeature f;
    f.fid = fid++;
    f.closed = closed;
    f.hasZ = true;
    f.vertices = std::move(line);
    layer.features.push_back(std::move(f));
  }
  return layer;
}

IngestedLayer pointLayer(const std::string& name, FeatureKind kind, std::vector<Point3> points) {
  IngestedLayer layer;
  layer.config.name = name;
  layer.kind = kind;
  layer.points = std::move(points);
  for (std::size_t i = 0; i < layer.points.size(); ++i)
    layer.pointIds.push_back(static_cast<std::int64_t>(i + 10));
  return layer;
}

CleanOptions tolerance(double t) {
  CleanOptions o;
  o.tolerance = t;
  return o;
}

TEST(Clean, SnapsVerticesOntoHigherPriorityFeatures) {
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("contours", FeatureKind::Contour, {{{0.0005, 0, 100}, {10, 0, 100}}}));
  layers.push_back(lineLayer("road", FeatureKind::Road, {{{0, 0, 99}, {0, 10, 99}}}));
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.verticesSnapped, 1u);
  // The road (higher priority) keeps its position; the contour vertex moves
  // onto it and keeps its own z.
  EXPECT_EQ(layers[0].features[0].vertices[0], (Point3{0, 0, 100}));
  EXPECT_EQ(layers[1].features[0].vertices[0], (Point3{0, 0, 99}));
}

TEST(Clean, DropsRepeatedVerticesAndZeroLengthSegments) {
  std::vector<IngestedLayer> layers;
  layers.push_back(
      lineLayer("road", FeatureKind::Road,
                {{{0, 0, 1}, {0, 0, 1}, {1, 0, 1}, {1, 0.0001, 1}, {2, 0, 1}, {2, 0, 1}}}));
  layers.push_back(lineLayer("lake", FeatureKind::Lake,
                             {{{0, 5, 3}, {4, 5, 3}, {4, 9, 3}, {0, 9, 3}, {0.0002, 5, 3}}}, true));
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.repeatedVerticesDropped, 4u);  // three on the road, the lake's closing one
  const auto& road = layers[0].features[0].vertices;
  ASSERT_EQ(road.size(), 3u);
  EXPECT_EQ(road[1], (Point3{1, 0, 1}));
  EXPECT_EQ(layers[1].features[0].vertices.size(), 4u);
}

TEST(Clean, DropsDegenerateFeatures) {
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("river", FeatureKind::River,
                             {{{0, 0, 1}, {0, 0.0001, 1}}, {{5, 5, 1}, {6, 6, 1}}, {{9, 9, 1}}}));
  layers.push_back(
      lineLayer("hole", FeatureKind::Hole, {{{20, 20, 0}, {21, 20, 0}, {21, 20.0001, 0}}}, true));
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.degenerateFeaturesDropped, 3u);
  ASSERT_EQ(layers[0].features.size(), 1u);
  EXPECT_EQ(layers[0].features[0].fid, 2);
  EXPECT_TRUE(layers[1].features.empty());
}

TEST(Clean, MergesDuplicateAndNearDuplicatePoints) {
  std::vector<IngestedLayer> layers;
  // The DEM comes first in the config, but spot heights win a merge.
  layers.push_back(pointLayer("dem", FeatureKind::Raster, {{0, 0, 50}, {5, 5, 60}, {7, 7, 70}}));
  layers.push_back(
      pointLayer("spots", FeatureKind::SpotHeight,
                 {{0.0004, 0, 51}, {1, 1, 10}, {1, 1, 10}, {1.0003, 1, 10.5}, {3, 3, 30}}));
  layers.push_back(lineLayer("road", FeatureKind::Road, {{{3.0001, 3, 31}, {4, 4, 31}}}));
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.duplicatePointsMerged, 3u);      // (0,0) dem cell, (1,1) twice
  EXPECT_EQ(report.duplicatePointZConflicts, 2u);   // 50 vs 51, 10 vs 10.5
  EXPECT_EQ(report.pointsOnBreakLineVertices, 1u);  // (3,3) on the road's vertex
  ASSERT_EQ(layers[1].points.size(), 2u);
  EXPECT_EQ(layers[1].points[0], (Point3{0.0004, 0, 51}));
  EXPECT_EQ(layers[1].pointIds[1], 11);
  ASSERT_EQ(layers[0].points.size(), 2u);
  EXPECT_EQ(layers[0].points[0], (Point3{5, 5, 60}));
  EXPECT_EQ(layers[0].pointIds[0], 11);
}

TEST(Clean, ZeroToleranceMergesExactDuplicatesOnly) {
  std::vector<IngestedLayer> layers;
  layers.push_back(
      pointLayer("spots", FeatureKind::SpotHeight, {{1, 1, 1}, {1, 1, 1}, {1, 1.0000001, 1}}));
  const auto report = cleanLayers(layers, tolerance(0.0));
  EXPECT_EQ(report.duplicatePointsMerged, 1u);
  EXPECT_EQ(layers[0].points.size(), 2u);
}

TEST(Clean, CrossingContoursOfDifferentZAreReportedAndCutOut) {
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("contours", FeatureKind::Contour,
                             {{{0, 0, 100}, {10, 0, 100}, {20, 0, 100}, {30, 0, 100}},
                              {{15, -5, 120}, {15, 5, 120}, {15, 10, 120}},
                              {{25, -5, 100}, {25, 5, 100}}}));  // same z: allowed to meet
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.contourCrossings, 1u);
  EXPECT_EQ(report.contourSelfCrossings, 0u);
  ASSERT_EQ(report.crossings.size(), 1u);
  const auto& c = report.crossings[0];
  EXPECT_EQ(c.fidA, 1);
  EXPECT_EQ(c.fidB, 2);
  EXPECT_EQ(c.zA, 100);
  EXPECT_EQ(c.zB, 120);
  EXPECT_DOUBLE_EQ(c.at.x, 15);
  EXPECT_DOUBLE_EQ(c.at.y, 0);
  const auto text = describe(c);
  EXPECT_NE(text.find("feature 1"), std::string::npos) << text;
  EXPECT_NE(text.find("feature 2"), std::string::npos) << text;
  EXPECT_EQ(report.segmentsCutOut, 2u);
  // Feature 1 loses its middle segment (two pieces), feature 2 its first.
  const auto& f = layers[0].features;
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[0].fid, 1);
  EXPECT_EQ(f[0].vertices, (std::vector<Point3>{{0, 0, 100}, {10, 0, 100}}));
  EXPECT_EQ(f[1].fid, 1);
  EXPECT_EQ(f[1].vertices, (std::vector<Point3>{{20, 0, 100}, {30, 0, 100}}));
  EXPECT_EQ(f[2].fid, 2);
  EXPECT_EQ(f[2].vertices, (std::vector<Point3>{{15, 5, 120}, {15, 10, 120}}));
  EXPECT_EQ(f[3].fid, 3);
}

TEST(Clean, ContoursOfDifferentZTouchingAtAVertex) {
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("a", FeatureKind::Contour, {{{0, 0, 10}, {10, 0, 10}}}));
  layers.push_back(lineLayer("b", FeatureKind::Contour, {{{5, 0, 20}, {5, 10, 20}}}));
  const auto report = cleanLayers(layers, tolerance(0.001));
  ASSERT_EQ(report.contourCrossings, 1u);
  EXPECT_EQ(report.crossings[0].layerA, "a");
  EXPECT_EQ(report.crossings[0].layerB, "b");
}

TEST(Clean, SelfCrossingContour) {
  std::vector<IngestedLayer> layers;
  // A bow tie: segment 0 crosses segment 2. The closed square next to it has
  // only neighbouring segments meeting, across its seam too.
  layers.push_back(lineLayer("contours", FeatureKind::Contour,
                             {{{0, 0, 5}, {10, 10, 5}, {10, 0, 5}, {0, 10, 5}}}));
  auto square = lineLayer("ring", FeatureKind::Contour,
                          {{{20, 0, 5}, {30, 0, 5}, {30, 10, 5}, {20, 10, 5}}}, true);
  layers.push_back(square);
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.contourSelfCrossings, 1u);
  EXPECT_EQ(report.contourCrossings, 0u);
  ASSERT_EQ(report.crossings.size(), 1u);
  EXPECT_TRUE(report.crossings[0].self);
  EXPECT_NEAR(report.crossings[0].at.x, 5, 1e-12);
  EXPECT_NEAR(report.crossings[0].at.y, 5, 1e-12);
  ASSERT_EQ(layers[1].features.size(), 1u);
  EXPECT_TRUE(layers[1].features[0].closed);
  // The bow tie keeps its middle segment only.
  ASSERT_EQ(layers[0].features.size(), 1u);
  EXPECT_EQ(layers[0].features[0].vertices, (std::vector<Point3>{{10, 10, 5}, {10, 0, 5}}));
}

TEST(Clean, CrossingRingIsOpenedAtTheCut) {
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("ring", FeatureKind::Contour,
                             {{{0, 0, 5}, {10, 0, 5}, {10, 10, 5}, {0, 10, 5}}}, true));
  layers.push_back(lineLayer("line", FeatureKind::Contour, {{{5, -5, 7}, {5, 5, 7}}}));
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.contourCrossings, 1u);
  ASSERT_EQ(layers[0].features.size(), 1u);
  const auto& piece = layers[0].features[0];
  EXPECT_FALSE(piece.closed);
  EXPECT_EQ(piece.vertices, (std::vector<Point3>{{10, 0, 5}, {10, 10, 5}, {0, 10, 5}, {0, 0, 5}}));
  EXPECT_TRUE(layers[1].features.empty());
}

TEST(Clean, StrictModeThrowsNamingBothFeatures) {
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("contours", FeatureKind::Contour,
                             {{{0, 0, 100}, {10, 0, 100}}, {{5, -5, 120}, {5, 5, 120}}}));
  CleanOptions options = tolerance(0.001);
  options.strict = true;
  try {
    cleanLayers(layers, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    const std::string m = e.what();
    EXPECT_NE(m.find("feature 1"), std::string::npos) << m;
    EXPECT_NE(m.find("feature 2"), std::string::npos) << m;
    EXPECT_NE(m.find("strict"), std::string::npos) << m;
  }
}

TEST(Clean, ManyParallelContoursHaveNoFalseCrossings) {
  // 200 wavy contours, 1000 vertices each, 1 m apart and never meeting.
  std::vector<std::vector<Point3>> lines;
  for (int c = 0; c < 200; ++c) {
    std::vector<Point3> line;
    for (int i = 0; i < 1000; ++i) {
      const double x = 431000.0 + i * 0.7;
      line.push_back({x, 4514000.0 + c * 1.0 + 0.3 * std::sin(i * 0.1), 1600.0 + c});
    }
    lines.push_back(std::move(line));
  }
  // Plus one line that cuts across all of them.
  lines.push_back({{431100.05, 4513990.0, 5000}, {431100.05, 4514300.0, 5000}});
  std::vector<IngestedLayer> layers;
  layers.push_back(lineLayer("contours", FeatureKind::Contour, std::move(lines)));
  const auto report = cleanLayers(layers, tolerance(0.001));
  EXPECT_EQ(report.contourCrossings, 200u);
  EXPECT_EQ(report.contourSelfCrossings, 0u);
  EXPECT_EQ(report.verticesSnapped, 0u);
}

TEST(Clean, RedButteConfigEndToEnd) {
  const auto config =
      loadProjectConfig(std::filesystem::path(TINSMITH_SOURCE_DIR) / "config/red-butte.toml");
  std::vector<std::string> stages;
  Progress progress;
  progress.callback = [&](std::string_view stage, std::string_view, std::uint64_t, std::uint64_t) {
    if (stages.empty() || stages.back() != stage) stages.emplace_back(stage);
  };
  const auto result = loadLayers(config, &progress);
  ASSERT_EQ(result.layers.size(), 6u);
  EXPECT_EQ(result.crs, "EPSG:26912");
  EXPECT_EQ(result.cleaning.contourCrossings, 0u);  // gdal_contour output is clean
  EXPECT_EQ(result.cleaning.contourSelfCrossings, 0u);
  EXPECT_EQ(result.summaries[1].pointsRead, 400u);
  EXPECT_EQ(result.layers[0].kind, FeatureKind::Contour);
  EXPECT_EQ(result.layers[3].kind, FeatureKind::River);
  EXPECT_FALSE(result.layers[3].hasZ);
  EXPECT_EQ(result.timings.size(), 3u);
  EXPECT_NE(std::find(stages.begin(), stages.end(), "readers.ogr"), stages.end());
  EXPECT_NE(std::find(stages.begin(), stages.end(), "filters.clean"), stages.end());
  for (const auto& layer : result.layers) {
    EXPECT_EQ(layer.crs, "EPSG:26912");
    for (const auto& f : layer.features) {
      for (std::size_t i = 1; i < f.vertices.size(); ++i) {
        EXPECT_FALSE(f.vertices[i].x == f.vertices[i - 1].x &&
                     f.vertices[i].y == f.vertices[i - 1].y);
      }
    }
  }
}

TEST(Clean, ChathamConfigEndToEnd) {
  const auto config =
      loadProjectConfig(std::filesystem::path(TINSMITH_SOURCE_DIR) / "config/chatham.toml");
  const auto result = loadLayers(config);
  ASSERT_EQ(result.layers.size(), 3u);
  EXPECT_EQ(result.cleaning.contourSelfCrossings, 0u);
  for (const auto& f : result.layers[2].features) EXPECT_EQ(f.vertices[0].z, 0.0);
  // NZTM Chatham: eastings around 3.5e6, northings around 5.1e6.
  const auto& p = result.layers[0].features[0].vertices[0];
  EXPECT_GT(p.x, 3.4e6);
  EXPECT_LT(p.x, 3.6e6);
  EXPECT_GT(p.y, 5.0e6);
  EXPECT_LT(p.y, 5.2e6);
}

}  // namespace
}  // namespace tinsmith::ingest
