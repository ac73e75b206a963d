// config: typed structs from TOML; every bad key, type, file and CRS is an error
// naming the key and the line.
#include <gtest/gtest.h>

#include <fstream>

#include "core/base/error.hpp"
#include "ingest/config/project_config.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

struct Fixture {
  std::filesystem::path dir;
  std::filesystem::path config;
};

Fixture makeFixture(const std::string& name, const std::string& toml) {
  Fixture f;
  f.dir = test::scratchDir(name);
  std::ofstream(f.dir / "pts.csv") << "x,y,z\n1,2,3\n";
  std::ofstream(f.dir / "lines.geojson") << R"({"type":"FeatureCollection","features":[]})";
  f.config = f.dir / "project.toml";
  std::ofstream(f.config) << toml;
  return f;
}

Error configError(const std::string& name, const std::string& toml) {
  const auto f = makeFixture(name, toml);
  try {
    loadProjectConfig(f.config);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "config accepted:\n" << toml;
  return internalError("none");
}

TEST(Config, FullConfigToTypedStructs) {
  const auto f = makeFixture("config_full", R"(
[project]
name = "site"
crs = "EPSG:26912"

[[layer]]
path = "lines.geojson"
kind = "contours"
z = "elev"
weight = 2

[[layer]]
path = "pts.csv"
kind = "points"
crs = "EPSG:4326"
name = "survey"
delimiter = "comma"
header = true
x = "x"
y = "y"

[[layer]]
path = "lines.geojson"
layer = "coast"
kind = "contours"
z_value = 0.0

[tin]
snap_tolerance = 0.05
flat_triangle_repair = false
river_descent = true
strict = true

[fit]
max_error = 0.5
)");
  const auto config = loadProjectConfig(f.config);
  EXPECT_EQ(config.name, "site");
  EXPECT_EQ(config.crs, "EPSG:26912");
  ASSERT_EQ(config.layers.size(), 3u);
  const auto& contours = config.layers[0];
  EXPECT_EQ(contours.kind, LayerKind::Contours);
  EXPECT_EQ(contours.zAttribute, "elev");
  EXPECT_EQ(contours.weight, 2.0);
  EXPECT_EQ(contours.path, (f.dir / "lines.geojson").lexically_normal());
  EXPECT_EQ(contours.name, "lines.geojson");
  EXPECT_EQ(contours.configLine, 6);
  const auto& survey = config.layers[1];
  EXPECT_EQ(survey.name, "survey");
  EXPECT_EQ(survey.crs, "EPSG:4326");
  EXPECT_EQ(survey.delimiter, TextDelimiter::Comma);
  EXPECT_EQ(survey.header, TextHeader::Present);
  EXPECT_EQ(config.layers[2].name, "lines.geojson:coast");
  EXPECT_EQ(config.layers[2].zValue, 0.0);
  EXPECT_EQ(config.tin.snapTolerance, 0.05);
  EXPECT_FALSE(config.tin.flatTriangleRepair);
  EXPECT_TRUE(config.tin.strict);
  ASSERT_EQ(config.extraTables.count("fit"), 1u);
  EXPECT_NE(config.extraTables.at("fit").toml.find("max_error = 0.5"), std::string::npos);
  EXPECT_EQ(featureKind(contours.kind), FeatureKind::Contour);
}

TEST(Config, Defaults) {
  const auto f = makeFixture("config_defaults", "[project]\ncrs = \"EPSG:32619\"\n");
  const auto config = loadProjectConfig(f.config);
  EXPECT_EQ(config.name, "project");
  EXPECT_TRUE(config.layers.empty());
  EXPECT_EQ(config.tin.snapTolerance, 0.001);
  EXPECT_TRUE(config.tin.flatTriangleRepair);
  EXPECT_TRUE(config.tin.riverDescent);
  EXPECT_FALSE(config.tin.strict);
}

TEST(Config, UnknownKeyNamesKeyAndLine) {
  auto e = configError("config_unknown", "[project]\ncrs = \"EPSG:26912\"\ncolour = \"red\"\n");
  EXPECT_EQ(e.kind(), ErrorKind::Input);
  EXPECT_EQ(e.where().file, "project.toml");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_NE(std::string(e.what()).find("unknown key 'colour'"), std::string::npos) << e.what();

  e = configError("config_unknown_layer",
                  "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\nkind = "
                  "\"points\"\nzz = \"h\"\n");
  EXPECT_EQ(e.where().line, 6);
  EXPECT_NE(std::string(e.what()).find("'zz'"), std::string::npos) << e.what();

  e = configError("config_unknown_table",
                  "[project]\ncrs = \"EPSG:26912\"\n[tinn]\nstrict = true\n");
  EXPECT_NE(std::string(e.what()).find("'tinn'"), std::string::npos) << e.what();

  e = configError("config_unknown_tin", "[project]\ncrs = \"EPSG:26912\"\n[tin]\nsnap = 1.0\n");
  EXPECT_EQ(e.where().line, 4);
}

TEST(Config, WrongTypes) {
  auto e = configError(
      "config_type_weight",
      "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\nkind = \"points\"\n"
      "weight = \"heavy\"\n");
  EXPECT_EQ(e.where().line, 6);
  EXPECT_NE(std::string(e.what()).find("weight must be a number, not a string"), std::string::npos)
      << e.what();

  e = configError("config_type_strict", "[project]\ncrs = \"EPSG:26912\"\n[tin]\nstrict = 1\n");
  EXPECT_NE(std::string(e.what()).find("tin.strict must be true or false"), std::string::npos)
      << e.what();

  e = configError("config_type_crs", "[project]\ncrs = 26912\n");
  EXPECT_NE(std::string(e.what()).find("project.crs must be a string"), std::string::npos)
      << e.what();

  e = configError("config_type_layer", "[project]\ncrs = \"EPSG:26912\"\nlayer = 3\n");
  EXPECT_NE(std::string(e.what()).find("unknown key 'layer' in [project]"), std::string::npos)
      << e.what();

  e = configError("config_type_root_layer", "layer = 3\n[project]\ncrs = \"EPSG:26912\"\n");
  EXPECT_EQ(e.where().line, 1);
  EXPECT_NE(std::string(e.what()).find("[[layer]]"), std::string::npos) << e.what();
}

TEST(Config, BadValues) {
  auto e = configError("config_kind",
                       "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\n"
                       "kind = \"mountain\"\n");
  EXPECT_EQ(e.where().line, 5);
  EXPECT_NE(std::string(e.what()).find("unknown kind 'mountain'"), std::string::npos) << e.what();

  e = configError("config_nokind",
                  "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\n");
  EXPECT_NE(std::string(e.what()).find("no 'kind'"), std::string::npos) << e.what();

  e = configError("config_missing_file",
                  "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"gone.gpkg\"\n"
                  "kind = \"contours\"\n");
  EXPECT_EQ(e.where().line, 4);
  EXPECT_NE(std::string(e.what()).find("gone.gpkg"), std::string::npos) << e.what();

  e = configError("config_both_z",
                  "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\n"
                  "kind = \"points\"\nz = \"h\"\nz_value = 1\n");
  EXPECT_NE(std::string(e.what()).find("not both"), std::string::npos) << e.what();

  e = configError("config_band",
                  "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\n"
                  "kind = \"points\"\nband = 2\n");
  EXPECT_NE(std::string(e.what()).find("dem"), std::string::npos) << e.what();

  e = configError("config_toml", "[project\ncrs = \"EPSG:26912\"\n");
  EXPECT_EQ(e.where().line, 1);
  EXPECT_NE(std::string(e.what()).find("not valid TOML"), std::string::npos) << e.what();

  e = configError(
      "config_dup",
      "[project]\ncrs = \"EPSG:26912\"\n[[layer]]\npath = \"pts.csv\"\nkind = \"points\"\n"
      "[[layer]]\npath = \"pts.csv\"\nkind = \"points\"\n");
  EXPECT_NE(std::string(e.what()).find("two layers"), std::string::npos) << e.what();
}

TEST(Config, TilesKeysToTileJobOptions) {
  const auto f = makeFixture("config_tiles", R"([project]
crs = "EPSG:26912"

[tiles]
tolerance = 2.5
max_triangles = 4096
max_zoom = 7
lambda = 0.1
compression = "none"
frame = "local"
geoid = "egm96"
output = "out/site.3dtiles"
)");
  const auto config = loadProjectConfig(f.config);
  const TilesConfig& t = config.tiles;
  EXPECT_EQ(t.configLine, 4);
  EXPECT_EQ(t.job.tiler.tolerance, 2.5);
  EXPECT_EQ(t.job.tiler.maxTriangles, 4096u);
  EXPECT_EQ(t.job.tiler.maxZoom, 7);
  EXPECT_EQ(t.job.tiler.lambdaFactor, 0.1);
  EXPECT_EQ(t.job.compression, encode::Compression::None);
  EXPECT_EQ(t.job.frame, tiles::ContentFrame::Local);
  EXPECT_EQ(t.job.geoid, "egm96");
  EXPECT_EQ(t.output, (f.dir / "out/site.3dtiles").lexically_normal());
  EXPECT_EQ(config.extraTables.count("tiles"), 0u);

  // An integer tolerance is a number; an absolute output stays as written.
  const auto g = makeFixture("config_tiles_int",
                             "[project]\ncrs = \"EPSG:26912\"\n[tiles]\ntolerance = 3\n"
                             "output = \"/srv/tiles/site\"\n");
  const auto other = loadProjectConfig(g.config);
  EXPECT_EQ(other.tiles.job.tiler.tolerance, 3.0);
  EXPECT_EQ(other.tiles.output, std::filesystem::path("/srv/tiles/site"));
}

TEST(Config, TilesKeysLeftOutAreTheTileCommandsDefaults) {
  const auto f = makeFixture("config_tiles_defaults", "[project]\ncrs = \"EPSG:26912\"\n[tiles]\n");
  const auto config = loadProjectConfig(f.config);
  const TileJobOptions defaults;
  const TileJobOptions& t = config.tiles.job;
  EXPECT_EQ(t.tiler.tolerance, defaults.tiler.tolerance);
  EXPECT_EQ(t.tiler.maxTriangles, defaults.tiler.maxTriangles);
  EXPECT_FALSE(t.tiler.maxZoom.has_value());
  EXPECT_EQ(t.tiler.lambdaFactor, defaults.tiler.lambdaFactor);
  EXPECT_EQ(t.compression, encode::Compression::Draco);
  EXPECT_EQ(t.frame, tiles::ContentFrame::Ecef);
  EXPECT_EQ(t.geoid, "");
  EXPECT_TRUE(config.tiles.output.empty());
  EXPECT_EQ(config.tiles.configLine, 3);
  EXPECT_EQ(
      loadProjectConfig(makeFixture("config_no_tiles", "[project]\ncrs = \"EPSG:26912\"\n").config)
          .tiles.configLine,
      0);
}

TEST(Config, BadTilesKeysNameTheFileLineKeyAndValue) {
  struct Case {
    const char* line;
    const char* expected;  // in the message, besides the file name
    const char* hint;      // in the hint
  };
  const Case cases[] = {
      {"tolerance = 0", "tiles.tolerance = 0: must be greater than 0", "tolerance = 1"},
      {"tolerance = -1.5", "tiles.tolerance = -1.5: must be greater than 0", "tolerance = 1"},
      {"tolerance = \"5\"", "tiles.tolerance must be a number, not a string (\"5\")",
       "write a number without quotes"},
      {"max_triangles = 10", "tiles.max_triangles = 10: must be at least 64", "32768"},
      {"max_triangles = 1e4", "tiles.max_triangles must be an integer, not a number", ""},
      {"max_zoom = 31", "tiles.max_zoom = 31: must be 0 to 30", "leave it out"},
      {"max_zoom = -1", "tiles.max_zoom = -1: must be 0 to 30", ""},
      {"lambda = 0", "tiles.lambda = 0: must be greater than 0", "0.01"},
      {"compression = \"zstd\"", "tiles.compression = \"zstd\": unknown compression",
       "\"draco\" | \"none\""},
      {"frame = \"enu\"", "tiles.frame = \"enu\": unknown frame", "\"local\""},
      {"geoid = \"egm2008\"", "tiles.geoid = \"egm2008\": unknown geoid", "egm96"},
      {"output = \"\"", "tiles.output = \"\": is empty", ".3dtiles"},
      {"threads = 2", "unknown key 'threads' in [tiles]", "allowed keys: attribution, compression, frame"},
  };
  for (const auto& c : cases) {
    const auto e =
        configError("config_tiles_bad",
                    std::string("[project]\ncrs = \"EPSG:26912\"\n[tiles]\n") + c.line + "\n");
    EXPECT_EQ(e.kind(), ErrorKind::Input) << c.line;
    EXPECT_EQ(e.where().file, "project.toml") << c.line;
    EXPECT_EQ(e.where().line, 4) << c.line;
    EXPECT_NE(e.problem().find(c.expected), std::string::npos) << c.line << ": " << e.what();
    EXPECT_NE(e.hint().find(c.hint), std::string::npos) << c.line << ": " << e.what();
  }
  const auto e =
      configError("config_tiles_not_table", "tiles = 5\n[project]\ncrs = \"EPSG:26912\"\n");
  EXPECT_NE(std::string(e.what()).find("'tiles' must be a table"), std::string::npos) << e.what();
}

TEST(Config, ProjectCrsMustBeProjectedMetres) {
  auto e = configError("config_geographic", "[project]\ncrs = \"EPSG:4326\"\n");
  EXPECT_EQ(e.where().line, 2);
  EXPECT_NE(std::string(e.what()).find("not a projected CRS"), std::string::npos) << e.what();

  e = configError("config_feet", "[project]\ncrs = \"EPSG:2227\"\n");  // California zone 3, US feet
  EXPECT_NE(std::string(e.what()).find("metres"), std::string::npos) << e.what();

  e = configError("config_nonsense_crs", "[project]\ncrs = \"EPSG:999999\"\n");
  EXPECT_NE(std::string(e.what()).find("not a CRS"), std::string::npos) << e.what();

  e = configError("config_no_crs", "[project]\nname = \"x\"\n");
  EXPECT_NE(std::string(e.what()).find("no 'crs'"), std::string::npos) << e.what();
}

TEST(Config, MissingConfigFile) {
  try {
    loadProjectConfig("/nonexistent/site.toml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/site.toml"), std::string::npos);
  }
}

TEST(Config, ExampleConfigsLoad) {
  for (const char* name : {"red-butte.toml", "chatham.toml"}) {
    const auto config =
        loadProjectConfig(std::filesystem::path(TINSMITH_SOURCE_DIR) / "config" / name);
    EXPECT_FALSE(config.layers.empty()) << name;
  }
}

}  // namespace
}  // namespace tinsmith::ingest
