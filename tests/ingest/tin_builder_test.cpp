// builders.tin on synthetic layers (rivers, roads, lakes, boundary) and on
// the real Chatham contours (flat-triangle repair) through loadLayers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "core/base/error.hpp"
#include "core/mesh/validate.hpp"
#include "ingest/build/flat_triangles.hpp"
#include "ingest/build/from_ingest.hpp"
#include "ingest/build/tin_builder.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/pipeline/load_layers.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

double plane(double x, double y) { return 100.0 + 0.1 * x + 0.02 * y; }

BuildLayer gridPoints(double step = 10.0, double size = 100.0) {
  BuildLayer layer;
  layer.name = "grid";
  layer.kindName = "points";
  layer.kind = FeatureKind::SpotHeight;
  layer.source = "grid.csv";
  for (double y = 0; y <= size; y += step)
    for (double x = 0; x <= size; x += step) layer.points.push_back({x, y, plane(x, y)});
  return layer;
}

BuildLayer lineLayer(FeatureKind kind, const std::string& name, std::vector<Point3> vertices,
                     bool closed = false, bool hasZ = false) {
  BuildLayer layer;
  layer.name = name;
  layer.kindName = name;
  layer.kind = kind;
  layer.source = name + ".geojson";
  for (auto& v : vertices)
    if (!hasZ) v.z = std::nan("");
  layer.lines.push_back({std::move(vertices), closed, hasZ, name + ".geojson, feature 0"});
  return layer;
}

std::set<std::uint32_t> featuresOfKind(const TinData& tin, FeatureKind kind) {
  std::set<std::uint32_t> ids;
  for (std::uint32_t f = 0; f < tin.features.size(); ++f)
    if (tin.features[f].kind == kind) ids.insert(f);
  return ids;
}

std::vector<TinData::ConstrainedEdge> edgesOfKind(const TinData& tin, FeatureKind kind) {
  const auto ids = featuresOfKind(tin, kind);
  std::vector<TinData::ConstrainedEdge> out;
  for (const auto& e : tin.constrainedEdges)
    if (ids.count(e.feature)) out.push_back(e);
  return out;
}

bool inside(double x, double y, double lo, double hi) { return x > lo && x < hi && y > lo && y < hi; }

TEST(TinBuilder, PointsOnlyMakeAValidTinWithEveryPointAVertex) {
  const auto r = buildTin({gridPoints()}, {});
  EXPECT_TRUE(validate(r.tin).ok) << validate(r.tin).summary();
  EXPECT_EQ(r.tin.vertices.size(), 121u);
  EXPECT_EQ(r.tin.triangles.size(), 200u);
  EXPECT_TRUE(r.report.valid);
  EXPECT_EQ(r.report.inputPoints, 121u);
  EXPECT_EQ(r.report.minZ, 100.0);
  EXPECT_DOUBLE_EQ(r.report.maxZ, plane(100, 100));
}

TEST(TinBuilder, RiverDigitisedUpstreamIsDrapedMadeToDescendAndConstrained) {
  BuildLayer points = gridPoints();
  points.points.push_back({50, 52, 180});  // a mound the river must not climb
  // Digitised from the low (west) end to the high (east) end: upstream.
  auto river = lineLayer(FeatureKind::River, "river", {{3, 51, 0}, {48, 51, 0}, {97, 51, 0}});
  const auto r = buildTin({points, river}, {});
  ASSERT_TRUE(validate(r.tin).ok) << validate(r.tin).summary();
  EXPECT_EQ(r.report.riversDraped, 1u);
  EXPECT_EQ(r.report.riversReversed, 1u);
  EXPECT_GT(r.report.riverVerticesAdjusted, 0u);
  // The largest change is reported where it is, with its river and heights,
  // and the summary names it.
  ASSERT_EQ(r.report.riverLargestChanges.size(), 1u);
  const auto& change = r.report.riverLargestChanges[0];
  EXPECT_DOUBLE_EQ(std::abs(change.zOther - change.zKept), r.report.riverMaxAdjustment);
  EXPECT_EQ(change.at.y, 51.0);
  EXPECT_NE(change.what.find("river"), std::string::npos) << change.what;
  EXPECT_NE(r.report.summary().find("lowered from"), std::string::npos) << r.report.summary();
  const auto edges = edgesOfKind(r.tin, FeatureKind::River);
  ASSERT_GE(edges.size(), 9u);  // densified to ≤ 10 m
  // Along every river edge, z falls (or stays) towards the west: downstream.
  for (const auto& e : edges) {
    const Point3& a = r.tin.vertices[e.a];
    const Point3& b = r.tin.vertices[e.b];
    const Point3& west = a.x < b.x ? a : b;
    const Point3& east = a.x < b.x ? b : a;
    EXPECT_LE(west.z, east.z) << west.x << " → " << east.x;
    EXPECT_EQ(a.y, 51.0);
  }
  // The mound itself stays a vertex at its surveyed height.
  const auto mound = std::find(r.tin.vertices.begin(), r.tin.vertices.end(), Point3{50, 52, 180});
  EXPECT_NE(mound, r.tin.vertices.end());
}

TEST(TinBuilder, River3DIsCheckedAndFixedNotDraped) {
  auto river = lineLayer(FeatureKind::River, "river", {{5, 20, 140}, {50, 20, 150}, {95, 20, 120}}, false, true);
  const auto r = buildTin({gridPoints(), river}, {});
  EXPECT_EQ(r.report.riversDraped, 0u);
  EXPECT_EQ(r.report.riversChecked, 1u);
  EXPECT_EQ(r.report.riversReversed, 0u);
  // The rise 140 → 150 pools to the length-weighted mean: weights 22.5 and
  // 45 (half the adjacent segment lengths), (140·22.5 + 150·45) / 67.5.
  const double pooled = (140 * 22.5 + 150 * 45) / 67.5;
  EXPECT_EQ(r.report.riverVerticesAdjusted, 2u);
  EXPECT_DOUBLE_EQ(r.report.riverMaxAdjustment, pooled - 140);
  bool found = false;
  for (const auto& v : r.tin.vertices)
    if (v.x == 50 && v.y == 20) {
      EXPECT_DOUBLE_EQ(v.z, pooled);
      found = true;
    }
  EXPECT_TRUE(found);
}

TEST(TinBuilder, RiverDescentCanBeSwitchedOff) {
  auto river = lineLayer(FeatureKind::River, "river", {{5, 20, 140}, {50, 20, 150}, {95, 20, 120}}, false, true);
  BuildOptions options;
  options.riverDescent = false;
  const auto r = buildTin({gridPoints(), river}, options);
  EXPECT_EQ(r.report.riverVerticesAdjusted, 0u);
  EXPECT_NE(std::find(r.tin.vertices.begin(), r.tin.vertices.end(), Point3{50, 20, 150}), r.tin.vertices.end());
}

TEST(TinBuilder, Road2DIsDrapedSmoothedAndCrossingARiverIsABridgeCandidate) {
  BuildLayer points = gridPoints();
  points.points.push_back({41, 44, 160});  // a bad survey point beside the road
  auto road = lineLayer(FeatureKind::Road, "road", {{2, 2, 0}, {98, 98, 0}});
  auto river = lineLayer(FeatureKind::River, "river", {{2, 90, 0}, {90, 2, 0}});
  const auto r = buildTin({points, road, river}, {});
  ASSERT_TRUE(validate(r.tin).ok) << validate(r.tin).summary();
  EXPECT_EQ(r.report.roadsDraped, 1u);
  ASSERT_EQ(r.report.bridgeCandidates.size(), 1u);
  EXPECT_NEAR(r.report.bridgeCandidates[0].at.x, 46.0, 1e-6);
  EXPECT_NEAR(r.report.bridgeCandidates[0].at.y, 46.0, 1e-6);
  EXPECT_NE(r.report.bridgeCandidates[0].what.find("road"), std::string::npos);
  // The road has no spike: neighbouring road vertices differ by a grade, not a cliff.
  for (const auto& e : edgesOfKind(r.tin, FeatureKind::Road)) {
    const Point3& a = r.tin.vertices[e.a];
    const Point3& b = r.tin.vertices[e.b];
    const double run = std::hypot(b.x - a.x, b.y - a.y);
    EXPECT_LT(std::abs(b.z - a.z) / run, 1.0) << a.x << "," << a.y;
  }
}

TEST(TinBuilder, LakeIsFlatAtItsLowestShoreLevelAndDropsWhatIsInside) {
  auto lake = lineLayer(FeatureKind::Lake, "lake", {{35, 35, 0}, {65, 35, 0}, {65, 65, 0}, {35, 65, 0}}, true);
  // A contour that runs through the lake is cut at its last vertex outside.
  BuildLayer contour;
  contour.name = contour.kindName = "contours";
  contour.kind = FeatureKind::Contour;
  contour.source = "contours.gpkg";
  contour.lines.push_back({{{0, 50, 105}, {30, 50, 105}, {50, 50, 105}, {70, 50, 105}, {100, 50, 105}},
                           false, true, "contours.gpkg, feature 1"});
  const auto r = buildTin({gridPoints(), contour, lake}, {});
  ASSERT_TRUE(validate(r.tin).ok) << validate(r.tin).summary();
  ASSERT_EQ(r.report.lakes.size(), 1u);
  const double level = r.report.lakes[0].level;
  EXPECT_DOUBLE_EQ(level, plane(35, 35));
  // 9 grid points and one contour vertex inside the lake are gone.
  std::size_t droppedInside = 0;
  for (const auto& [name, count] : r.report.cleaning)
    if (name.find("inside lakes") != std::string::npos) droppedInside = count;
  EXPECT_EQ(droppedInside, 10u);
  std::size_t lakeTriangles = 0;
  for (const auto& t : r.tin.triangles) {
    const auto& a = r.tin.vertices[t[0]];
    const auto& b = r.tin.vertices[t[1]];
    const auto& c = r.tin.vertices[t[2]];
    if (!inside((a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3, 35, 65)) continue;
    ++lakeTriangles;
    EXPECT_EQ(a.z, level);
    EXPECT_EQ(b.z, level);
    EXPECT_EQ(c.z, level);
  }
  EXPECT_GE(lakeTriangles, 2u);
  EXPECT_FALSE(edgesOfKind(r.tin, FeatureKind::Lake).empty());
}

TEST(TinBuilder, BoundaryClipsTheTinAndIsDraped) {
  auto boundary = lineLayer(FeatureKind::Boundary, "boundary", {{10, 10, 0}, {90, 10, 0}, {90, 90, 0}, {10, 90, 0}}, true);
  const auto r = buildTin({gridPoints(), boundary}, {});
  ASSERT_TRUE(validate(r.tin).ok) << validate(r.tin).summary();
  for (const auto& v : r.tin.vertices) {
    EXPECT_GE(v.x, 10.0);
    EXPECT_LE(v.x, 90.0);
    EXPECT_DOUBLE_EQ(v.z, plane(v.x, v.y));
  }
  EXPECT_EQ(r.tin.triangles.size(), 128u);  // the 8 × 8 cells inside, two triangles each
}

TEST(TinBuilder, ErrorsNameTheFeature) {
  BuildLayer contour;
  contour.name = contour.kindName = "contours";
  contour.kind = FeatureKind::Contour;
  contour.lines.push_back({{{0, 0, 0}, {1, 1, 0}}, false, false, "c.gpkg, feature 9"});
  try {
    buildTin({gridPoints(), contour}, {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("c.gpkg, feature 9"), std::string::npos);
  }
  // A 2D river far away from the surface.
  auto river = lineLayer(FeatureKind::River, "river", {{1000, 1000, 0}, {1100, 1000, 0}});
  try {
    buildTin({gridPoints(), river}, {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Geometry);
    EXPECT_NE(std::string(e.what()).find("river.geojson, feature 0"), std::string::npos);
  }
  EXPECT_THROW(buildTin({}, {}), Error);
}

TEST(TinBuilder, SameInputSameBytes) {
  auto river = lineLayer(FeatureKind::River, "river", {{3, 50, 0}, {48, 50, 0}, {97, 50, 0}});
  const auto a = buildTin({gridPoints(), river}, {});
  const auto b = buildTin({gridPoints(), river}, {});
  EXPECT_EQ(encodeTin(a.tin), encodeTin(b.tin));
}

TEST(TinBuilder, ReportRendersAsJsonAndSummary) {
  auto river = lineLayer(FeatureKind::River, "river", {{3, 50, 0}, {48, 50, 0}, {97, 50, 0}});
  const auto r = buildTin({gridPoints(), river}, {});
  const auto j = nlohmann::json::parse(r.report.toJson());
  EXPECT_EQ(j["result"]["vertices"], r.tin.vertices.size());
  EXPECT_EQ(j["rivers"]["reversed"], 1);
  EXPECT_EQ(j["layers"].size(), 2u);
  EXPECT_EQ(j["layers"][0]["points"], 121);
  EXPECT_TRUE(j["result"]["valid"].get<bool>());
  EXPECT_FALSE(j["times"].empty());
  const std::string s = r.report.summary();
  EXPECT_NE(s.find("1 draped"), std::string::npos) << s;
  EXPECT_NE(s.find("validation: ok"), std::string::npos) << s;
}

// Real contour-only data: flat triangles appear and the repair removes them.
TEST(TinBuilder, ChathamFlatTrianglesDropToNearZero) {
  const auto config =
      loadProjectConfig(std::filesystem::path(TINSMITH_SOURCE_DIR) / "config/chatham.toml");
  auto ingested = loadLayers(config);
  const auto layers = toBuildLayers(std::move(ingested.layers));
  BuildOptions off = buildOptionsFrom(config);
  off.flatTriangleRepair = false;
  const auto raw = buildTin(layers, off);
  const std::size_t before = countFlatTriangles(raw.tin);
  EXPECT_GT(before, 100u);
  EXPECT_EQ(raw.report.flatBefore, before);

  const auto fixed = buildTin(layers, buildOptionsFrom(config));
  EXPECT_EQ(fixed.report.flatBefore, before);
  EXPECT_LE(fixed.report.flatAfter, before / 100) << fixed.report.summary();
  EXPECT_EQ(countFlatTriangles(fixed.tin), fixed.report.flatAfter);
  EXPECT_GT(fixed.report.flatVerticesAdded, 0u);
  ASSERT_TRUE(validate(fixed.tin).ok) << validate(fixed.tin).summary();
  // The added vertices stay within the contour range ± one interval.
  EXPECT_GE(fixed.report.minZ, -20.0);
  EXPECT_LE(fixed.report.maxZ, 240.0);

  // The raw TIN analysed as a Mesh (as the builder does) and as TinData agree.
  const Mesh mesh = Mesh::fromTinData(raw.tin);
  const auto m = analyseFlatTriangles(mesh, 0.01), t = analyseFlatTriangles(raw.tin, 0.01);
  EXPECT_EQ(m.flatTriangles, t.flatTriangles);
  EXPECT_EQ(m.regions, t.regions);
  EXPECT_EQ(m.closedRegions, t.closedRegions);
  EXPECT_EQ(m.proposals, t.proposals);
  EXPECT_EQ(countFlatTriangles(mesh), before);

  // buildTinInto hands over the mesh; written, it is the same file, with the
  // same report, as buildTin's TinData written.
  const auto dir = test::scratchDir("builder-into");
  const BuildReport into = buildTinInto(layers, buildOptionsFrom(config), [&](const Mesh& out) {
    writeTinFile(dir / "into.tin", out);
  });
  writeTinFile(dir / "tin.tin", fixed.tin);
  EXPECT_EQ(test::readFile(dir / "into.tin"), test::readFile(dir / "tin.tin"));
  EXPECT_EQ(into.vertices, fixed.report.vertices);
  EXPECT_EQ(into.triangles, fixed.report.triangles);
  EXPECT_EQ(into.constrainedEdges, fixed.report.constrainedEdges);
  EXPECT_EQ(into.minZ, fixed.report.minZ);
  EXPECT_EQ(into.maxX, fixed.report.maxX);
  EXPECT_EQ(into.flatAfter, fixed.report.flatAfter);
}

// Release builds check the mesh's structure by default; the full validator
// (Delaunay, every input present) runs when asked, and in debug builds.
TEST(TinBuilder, ValidationLevels) {
  std::vector<BuildLayer> layers{gridPoints()};
  BuildOptions options;
#ifdef NDEBUG
  EXPECT_EQ(options.validation, BuildValidation::Structural);
#else
  EXPECT_EQ(options.validation, BuildValidation::Full);
#endif
  for (const auto& [level, name] : {std::pair{BuildValidation::Structural, "structural"},
                                   std::pair{BuildValidation::Full, "full"}}) {
    options.validation = level;
    const auto r = buildTin(layers, options);
    EXPECT_TRUE(r.report.valid);
    EXPECT_EQ(r.report.validation, name);
    EXPECT_NE(r.report.summary().find(std::string("validation: ok (") + name), std::string::npos)
        << r.report.summary();
  }
  options.validation = BuildValidation::Off;
  const auto r = buildTin(layers, options);
  EXPECT_FALSE(r.report.valid);
  EXPECT_EQ(r.report.validation, "off");
  EXPECT_NE(r.report.summary().find("validation: off"), std::string::npos);
}

}  // namespace
}  // namespace tinsmith::ingest
