// readers.synthetic: the same spec gives the same coordinates, the counts and
// degenerate layouts are what the spec says, bad specs name the spec and the
// key, and a synthetic project goes through the pipeline (reprojection,
// cleaning) and the TIN builder like files do.
#include "ingest/readers/synthetic_reader.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/surface/franke_function.hpp"
#include "ingest/build/from_ingest.hpp"
#include "ingest/readers/layer_reader.hpp"

namespace tinsmith::ingest {
namespace {

IngestedLayer synthetic(const std::string& spec, LayerKind kind = LayerKind::Points) {
  LayerConfig config;
  config.name = spec;
  config.path = spec;
  config.kind = kind;
  return readLayer(config);  // the dispatch the pipeline uses
}

/// The error a spec gives, or "" if it gives none.
Error errorOf(const std::string& spec, LayerKind kind = LayerKind::Points) {
  try {
    synthetic(spec, kind);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << spec << " gave no error";
  return internalError("none");
}

TEST(SyntheticReader, TheSameSpecGivesTheSameCoordinatesAndTheSeedChangesThem) {
  for (const std::string spec :
       {"synthetic:random?n=500&seed=7&surface=franke&noise=0.5&duplicates=3",
        "synthetic:grid?nx=9&ny=7&jitter=0.3&surface=hill",
        "synthetic:raster?nx=8&ny=6&nodata=0.2"}) {
    const auto a = synthetic(spec);
    const auto b = synthetic(spec);
    EXPECT_EQ(a.points, b.points) << spec;
    EXPECT_EQ(a.pointIds, b.pointIds) << spec;
  }
  const auto lines = "synthetic:lines?layout=random&n=4&vertices=5&seed=3";
  const auto l1 = synthetic(lines, LayerKind::Road);
  const auto l2 = synthetic(lines, LayerKind::Road);
  ASSERT_EQ(l1.features.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(l1.features[i].vertices, l2.features[i].vertices);

  const auto s1 = synthetic("synthetic:random?n=50&seed=1");
  const auto s2 = synthetic("synthetic:random?n=50&seed=2");
  EXPECT_NE(s1.points, s2.points);
  // The first values of seed 1, so a change of generator shows here.
  EXPECT_DOUBLE_EQ(s1.points[0].x, synthetic("synthetic:random?n=1").points[0].x);
}

TEST(SyntheticReader, AnExactGridIsExactAtUtmCoordinates) {
  const auto layer =
      synthetic("synthetic:grid?nx=4&ny=3&spacing=0.001&x0=500000&y0=4500000&surface=flat&z0=7");
  ASSERT_EQ(layer.points.size(), 12u);
  EXPECT_EQ(layer.kind, FeatureKind::SpotHeight);
  EXPECT_TRUE(layer.hasZ);
  for (std::size_t j = 0; j < 3; ++j) {
    for (std::size_t i = 0; i < 4; ++i) {
      const auto k = j * 4 + i;
      EXPECT_EQ(layer.points[k], (Point3{500000 + static_cast<double>(i) * 0.001,
                                         4500000 + static_cast<double>(j) * 0.001, 7.0}));
      EXPECT_EQ(layer.pointIds[k], static_cast<std::int64_t>(k));
    }
  }
}

TEST(SyntheticReader, CountsAndDegenerateOptions) {
  // Duplicates: exact copies of points already there.
  const auto dup = synthetic("synthetic:grid?nx=5&ny=5&duplicates=4");
  ASSERT_EQ(dup.points.size(), 29u);
  for (std::size_t k = 25; k < 29; ++k) {
    EXPECT_NE(std::find(dup.points.begin(), dup.points.begin() + 25, dup.points[k]),
              dup.points.begin() + 25);
  }
  // One row: a collinear run.
  const auto run = synthetic("synthetic:grid?nx=6&ny=1");
  ASSERT_EQ(run.points.size(), 6u);
  for (const auto& p : run.points) EXPECT_EQ(p.y, 0.0);

  EXPECT_EQ(synthetic("synthetic:random?n=123").points.size(), 123u);

  // A raster: cell centres, row 0 at the top; nodata leaves cells out.
  const auto raster = synthetic("synthetic:raster?nx=4&ny=2&spacing=2", LayerKind::Dem);
  ASSERT_EQ(raster.points.size(), 8u);
  EXPECT_EQ(raster.kind, FeatureKind::Raster);
  EXPECT_EQ(raster.points[0].x, 1.0);
  EXPECT_EQ(raster.points[0].y, 3.0);
  const auto holes = synthetic("synthetic:raster?nx=20&ny=20&nodata=0.5", LayerKind::Dem);
  EXPECT_GT(holes.points.size(), 100u);
  EXPECT_LT(holes.points.size(), 300u);
  const auto grid = syntheticHeightGrid("synthetic:raster?nx=20&ny=20&nodata=0.5");
  EXPECT_EQ(grid.width, 20);
  EXPECT_EQ(std::count_if(grid.z.begin(), grid.z.end(), [](float z) { return !std::isnan(z); }),
            static_cast<std::ptrdiff_t>(holes.points.size()));

  // Crossing lines: n horizontal and n vertical.
  const auto cross = synthetic("synthetic:lines?layout=cross&n=3&vertices=4", LayerKind::Road);
  ASSERT_EQ(cross.features.size(), 6u);
  EXPECT_EQ(cross.features[0].vertices.size(), 4u);
  EXPECT_EQ(cross.features[0].vertices.front(), (Point3{0, 25, 12.5}));  // plane: 100·(u+v)/2
  EXPECT_EQ(cross.features[3].vertices.back().y, 100.0);
  // A star: every line through the centre.
  const auto star = synthetic("synthetic:lines?layout=star&n=4&vertices=3", LayerKind::River);
  for (const auto& f : star.features) {
    EXPECT_NEAR(f.vertices[1].x, 50.0, 1e-12);
    EXPECT_NEAR(f.vertices[1].y, 50.0, 1e-12);
  }
  // 2D lines for the builder to drape.
  const auto flat = synthetic("synthetic:lines?z=none", LayerKind::Road);
  EXPECT_FALSE(flat.hasZ);
  EXPECT_TRUE(std::isnan(flat.features[0].vertices[0].z));

  // Rings: closed, one z each, the innermost highest.
  const auto rings =
      synthetic("synthetic:rings?n=3&interval=5&z0=100&vertices=8", LayerKind::Contours);
  ASSERT_EQ(rings.features.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const auto& f = rings.features[k];
    EXPECT_TRUE(f.closed);
    EXPECT_EQ(f.vertices.size(), 8u);
    for (const auto& v : f.vertices) EXPECT_EQ(v.z, 100.0 + 5.0 * static_cast<double>(3 - k));
  }
}

TEST(SyntheticReader, SurfacesAreTheDocumentedFormulas) {
  // franke over the unit square: scale 1 samples Franke's function itself.
  const auto franke = synthetic("synthetic:grid?nx=5&ny=5&spacing=0.25&surface=franke&scale=1");
  for (const auto& p : franke.points) EXPECT_DOUBLE_EQ(p.z, frankeFunction(p.x, p.y));
  const auto cone = synthetic("synthetic:grid?nx=3&ny=3&spacing=50&surface=cone&z0=10&scale=20");
  EXPECT_DOUBLE_EQ(cone.points[4].z, 30.0);  // the centre: the top
  EXPECT_DOUBLE_EQ(cone.points[0].z, 10.0);  // a corner: beyond the cone's foot
  const auto noisy = synthetic("synthetic:grid?surface=flat&noise=0.25");
  for (const auto& p : noisy.points) EXPECT_LE(std::abs(p.z), 0.25);
  // z_value overrides, as for files.
  LayerConfig config;
  config.path = "synthetic:lines?z=none";
  config.kind = LayerKind::Road;
  config.zValue = 3.0;
  const auto fixed = readLayer(config);
  EXPECT_TRUE(fixed.hasZ);
  EXPECT_EQ(fixed.features[0].vertices[0].z, 3.0);
}

TEST(SyntheticReader, BadSpecsNameTheSpecAndTheKey) {
  struct Case {
    std::string spec;
    LayerKind kind;
    std::string problem, hint;
  };
  const std::vector<Case> cases = {
      {"synthetic:blob", LayerKind::Points, "unknown pattern 'blob'", "grid, random, raster"},
      {"synthetic:grid?nz=3", LayerKind::Points, "unknown key 'nz' for pattern grid", "nx, ny"},
      {"synthetic:grid?n=3", LayerKind::Points, "unknown key 'n' for pattern grid", ""},
      {"synthetic:grid?nx=0", LayerKind::Points, "nx = 0 is out of range", "1 to 100000000"},
      {"synthetic:grid?nx=2.5", LayerKind::Points, "nx = 2.5 is not a whole number", ""},
      {"synthetic:grid?nx=1&ny=2", LayerKind::Points, "less than 3 points", ""},
      {"synthetic:grid?nx=100000&ny=100000", LayerKind::Points, "is too many", ""},
      // Each count within its range, the total not.
      {"synthetic:lines?n=100000000&vertices=100000000", LayerKind::Road,
       "would hold 10000000000000000 points or vertices, too many", "n × vertices"},
      {"synthetic:rings?n=20000&vertices=20000", LayerKind::Contours, "too many", ""},
      {"synthetic:random?n=60000000&duplicates=60000000", LayerKind::Points, "too many", ""},
      // Keys every pattern takes, where they do nothing.
      {"synthetic:rings?surface=hill", LayerKind::Contours,
       "key 'surface' does nothing for pattern rings", "leave it out"},
      {"synthetic:lines?z=none&scale=5", LayerKind::Road,
       "key 'scale' does nothing for lines with z=none", ""},
      // Each value finite, their sum not.
      {"synthetic:random?x0=1e308&width=1e308", LayerKind::Points, "extent", ""},
      {"synthetic:grid?z0=1e308&scale=1e308", LayerKind::Points, "not finite", ""},
      {"synthetic:grid?spacing=abc", LayerKind::Points, "spacing = 'abc' is not a number", ""},
      {"synthetic:grid?spacing=-1", LayerKind::Points, "spacing = -1 is out of range",
       "greater than 0"},
      {"synthetic:grid?jitter=0.7", LayerKind::Points, "jitter = 0.7 is out of range", "0 to 0.5"},
      {"synthetic:grid?surface=dome", LayerKind::Points, "surface = 'dome' is not known",
       "plane | flat | franke | hill | cone"},
      {"synthetic:grid?nx=3&nx=4", LayerKind::Points, "key 'nx' is given twice", ""},
      {"synthetic:grid?nx", LayerKind::Points, "key 'nx' has no value", ""},
      {"synthetic:random?seed=-1", LayerKind::Points, "seed = -1 is out of range", ""},
      {"synthetic:lines?layout=zigzag", LayerKind::Road, "layout = 'zigzag' is not known",
       "hatch | cross | star | random"},
      {"synthetic:lines?vertices=1", LayerKind::Road, "vertices = 1 is out of range", ""},
      {"synthetic:raster?nodata=1", LayerKind::Dem, "every cell is nodata", ""},
      {"synthetic:lines", LayerKind::Points,
       "pattern lines makes open lines, but kind = \"points\"", ""},
      {"synthetic:grid", LayerKind::Contours, "pattern grid makes points, but kind = \"contours\"",
       ""},
      {"synthetic:lines", LayerKind::Lake, "but kind = \"lake\" takes areas", "rings"},
  };
  for (const auto& c : cases) {
    const auto e = errorOf(c.spec, c.kind);
    EXPECT_EQ(e.kind(), ErrorKind::Input) << c.spec;
    EXPECT_EQ(e.where().file, c.spec);
    EXPECT_NE(e.problem().find(c.problem), std::string::npos) << c.spec << ": " << e.what();
    EXPECT_NE(e.hint().find(c.hint), std::string::npos) << c.spec << ": " << e.what();
  }
}

TEST(SyntheticReader, AProjectOfSyntheticLayersIsCheckedAtLoadAndBuildsAValidTin) {
  const auto config = parseProjectConfig(R"([project]
crs = "EPSG:32612"

[[layer]]
path = "synthetic:grid?nx=11&ny=11&spacing=10&x0=500000&y0=4500000&surface=hill&duplicates=5"
kind = "points"

[[layer]]
path = "synthetic:lines?layout=cross&n=2&x0=500000&y0=4500000&z=none"
kind = "road"

[[layer]]
path = "synthetic:rings?n=2&width=28&height=28&x0=500037&y0=4500037&z0=60"
kind = "contours"
name = "rings"
crs = "EPSG:32612"
)",
                                         "/nowhere/site.toml");
  ASSERT_EQ(config.layers.size(), 3u);
  EXPECT_EQ(config.layers[0].path.string(),
            "synthetic:grid?nx=11&ny=11&spacing=10&x0=500000&y0=4500000&surface=hill&duplicates=5");
  EXPECT_EQ(config.layers[0].name, config.layers[0].path.string());
  EXPECT_EQ(config.layers[2].name, "rings");

  const auto ingested = loadLayers(config);
  EXPECT_EQ(ingested.layers[0].crs, "EPSG:32612");  // no crs key: the project's
  EXPECT_EQ(ingested.summaries[0].pointsRead, 126u);
  EXPECT_EQ(ingested.summaries[0].pointsKept, 121u);  // filters.clean merged the duplicates

  BuildOptions options = buildOptionsFrom(config);
  options.validation = BuildValidation::Full;
  TinData tin;
  const auto report =
      buildTinFromConfig(config, options, [&](const Mesh& mesh) { tin = mesh.toTinData(); });
  EXPECT_EQ(report.validation, "full");
  EXPECT_EQ(report.crossings, 4u);  // two roads across two roads; the rings lie between them
  EXPECT_GE(tin.vertices.size(), 121u);
  EXPECT_GT(tin.constrainedEdges.size(), 0u);
  const auto again = buildTinFromConfig(config, options, [&](const Mesh& mesh) {
    EXPECT_EQ(mesh.toTinData().vertices, tin.vertices);
  });
  EXPECT_EQ(again.crossings, report.crossings);
}

TEST(SyntheticReader, ALayerWithItsOwnCrsIsReprojected) {
  // The same grid said to be in UTM 13N: filters.reproject moves it into 12N.
  const auto config = parseProjectConfig(R"([project]
crs = "EPSG:32612"
[[layer]]
path = "synthetic:grid?nx=3&ny=3&x0=200000&y0=4500000"
kind = "points"
crs = "EPSG:32613"
)",
                                         "/nowhere/site.toml");
  const auto ingested = loadLayers(config);
  const auto& p = ingested.layers[0].points[0];
  EXPECT_EQ(ingested.layers[0].sourceCrs, "EPSG:32613");
  EXPECT_GT(p.x, 600000.0);  // 6° further west: far east in zone 12
  EXPECT_NE(p.y, 4500000.0);
  EXPECT_EQ(p.z, 0.0);
}

TEST(SyntheticReader, BadSpecsInAConfigNameTheConfigLineAndTheKey) {
  auto messageOf = [](const std::string& layer) -> std::string {
    try {
      parseProjectConfig("[project]\ncrs = \"EPSG:32612\"\n[[layer]]\n" + layer,
                         "/nowhere/site.toml");
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  auto m = messageOf("kind = \"points\"\npath = \"synthetic:grid?spacing=0\"\n");
  EXPECT_NE(m.find("site.toml, line 5: [[layer]] #1.path: synthetic:grid?spacing=0: spacing = 0 "
                   "is out of range"),
            std::string::npos)
      << m;
  m = messageOf("kind = \"road\"\npath = \"synthetic:grid\"\n");
  EXPECT_NE(m.find("pattern grid makes points, but kind = \"road\""), std::string::npos) << m;
  m = messageOf("kind = \"points\"\npath = \"synthetic:grid\"\nz = \"elev\"\n");
  EXPECT_NE(m.find("a synthetic layer has no attributes"), std::string::npos) << m;
  m = messageOf("kind = \"points\"\npath = \"synthetic:grid\"\ndelimiter = \"tab\"\n");
  EXPECT_NE(m.find("a synthetic layer takes none of"), std::string::npos) << m;
}

}  // namespace
}  // namespace tinsmith::ingest
