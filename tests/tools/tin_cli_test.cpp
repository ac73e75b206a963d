// `tinsmith tin | validate | info | export | query` driven as a user would:
// plain inputs, the Red Butte config end to end (checked by the independent
// ../shared/tools/check_tin.py), and bad input — each a clear error with no
// partial output left behind.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "tests/support/run_command.hpp"

namespace tinsmith {
namespace {

namespace fs = std::filesystem;
using test::readFile;
using test::runCommand;
using test::runTinsmith;

const fs::path kShared = TINSMITH_SHARED_DATA;
const fs::path kSource = TINSMITH_SOURCE_DIR;
const std::string kChecker = (kShared.parent_path() / "tools/check_tin.py").string();

double plane(double x, double y) { return 1500.0 + 0.25 * x - 0.125 * y; }

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// Plain inputs: scattered points on a plane at UTM-sized coordinates, two
// crossing 3D GeoJSON break lines and one text polyline.
struct PlainInputs {
  fs::path dir, points, geojson, text;
};

PlainInputs makePlainInputs(const std::string& name) {
  PlainInputs in;
  in.dir = test::scratchDir(name);
  in.points = in.dir / "points.xyz";
  in.geojson = in.dir / "lines.geojson";
  in.text = in.dir / "ridge.txt";
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 400.0);
  std::string pts;
  char buf[128];
  for (int i = 0; i < 300; ++i) {
    const double x = u(rng), y = u(rng);
    std::snprintf(buf, sizeof buf, "%.6f %.6f %.6f\n", 431000 + x, 4512000 + y, plane(x, y));
    pts += buf;
  }
  writeText(in.points, pts);
  auto c = [](double x, double y) {
    char b[128];
    std::snprintf(b, sizeof b, "[%.3f, %.3f, %.6f]", 431000 + x, 4512000 + y, plane(x, y));
    return std::string(b);
  };
  writeText(in.geojson,
            "{\"type\": \"FeatureCollection\", \"features\": [\n"
            "{\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"LineString\", "
            "\"coordinates\": [" + c(20, 20) + ", " + c(200, 180) + ", " + c(380, 370) + "]}},\n"
            "{\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"MultiLineString\", "
            "\"coordinates\": [[" + c(20, 380) + ", " + c(380, 30) + "], [" + c(50, 200) + ", " + c(120, 210) + "]]}}\n"
            "]}\n");
  writeText(in.text, "# a ridge\n431100 4512300 " + std::to_string(plane(100, 300)) +
                         "\n431300 4512310 " + std::to_string(plane(300, 310)) + "\n\n431250 4512050 " +
                         std::to_string(plane(250, 50)) + "\n431260 4512150 " +
                         std::to_string(plane(260, 150)) + "\n");
  return in;
}

TEST(TinCli, PlainPointsAndBreakLinesMakeAValidTinThatTheCheckerAccepts) {
  const auto in = makePlainInputs("cli-plain");
  const fs::path tin = in.dir / "out.tin", obj = in.dir / "out.obj";
  auto r = runTinsmith("tin --points " + in.points.string() + " --breaklines " + in.geojson.string() +
                       " --breaklines " + in.text.string() + " -o " + tin.string() + " --crs EPSG:26912");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("validation: ok"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("crossings split: "), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("crossings split: 0"), std::string::npos) << r.err;
  r = runTinsmith("validate " + tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("valid"), std::string::npos);
  r = runTinsmith("export " + tin.string() + " --format obj -o " + obj.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // The text polylines as GeoJSON for the checker (it reads GeoJSON only).
  const fs::path allLines = in.dir / "all-lines.geojson";
  std::string geo = readFile(in.geojson);
  geo.insert(geo.rfind(']'),
             ",{\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"LineString\", "
             "\"coordinates\": [[431100, 4512300], [431300, 4512310]]}},"
             "{\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"LineString\", "
             "\"coordinates\": [[431250, 4512050], [431260, 4512150]]}}\n");
  writeText(allLines, geo);
  r = runCommand("python3 " + kChecker + " " + obj.string() + " " + in.points.string() + " " + allLines.string());
  EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
  EXPECT_EQ(r.out.rfind("ok", 0), 0u) << r.out;
}

TEST(TinCli, TheTinIsTheSameForAnyThreadCount) {
  // Enough points for the two-half parallel triangulation, plus crossing
  // break lines: the .tin files must be byte for byte the same.
  const fs::path dir = test::scratchDir("tin_threads");
  const std::string inputs =
      "--points 'synthetic:random?n=60300&seed=8&width=400&height=400&x0=431000&y0=4512000' "
      "--breaklines 'synthetic:lines?layout=random&n=3&vertices=3&seed=5&width=400&height=400"
      "&x0=431000&y0=4512000'";
  std::string previous;
  for (const char* threads : {"1", "2", "0"}) {
    const fs::path tin = dir / (std::string("t") + threads + ".tin");
    const auto r = runTinsmith("tin -q " + inputs + " --crs EPSG:26912 --threads " + threads +
                               " -o " + tin.string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string bytes = readFile(tin);
    EXPECT_GT(bytes.size(), 60000u * 24);
    if (!previous.empty()) {
      EXPECT_TRUE(bytes == previous) << "threads " << threads;
    }
    previous = bytes;
  }
}

// A grid whose west edge bows inwards, as a projected DEM's does: the hull
// closes it with slivers that --trim-hull removes, every point staying a
// vertex and the result a valid TIN with one boundary.
TEST(TinCli, TrimHullRemovesTheSliversOfACurvedEdge) {
  const fs::path dir = test::scratchDir("cli-trim-hull");
  std::string pts;
  char buf[128];
  for (int j = 0; j < 30; ++j) {
    const double bow = 300 * std::sin(3.14159265358979 * j / 29.0);
    for (int i = 0; i < 30; ++i) {
      std::snprintf(buf, sizeof buf, "%.3f %.3f %.3f\n", 431000 + 90.0 * i + bow, 4512000 + 90.0 * j,
                    1500.0 + i);
      pts += buf;
    }
  }
  writeText(dir / "grid.xyz", pts);
  const fs::path plain = dir / "plain.tin", trimmed = dir / "trimmed.tin";
  ASSERT_EQ(runTinsmith("tin -q --points " + (dir / "grid.xyz").string() + " -o " + plain.string()).exitCode, 0);
  auto r = runTinsmith("tin --points " + (dir / "grid.xyz").string() + " --trim-hull 270 -o " +
                       trimmed.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("hull trimmed: "), std::string::npos) << r.err;
  const auto before = nlohmann::json::parse(runTinsmith("info " + plain.string() + " --json").out);
  const auto after = nlohmann::json::parse(runTinsmith("info " + trimmed.string() + " --json").out);
  EXPECT_EQ(after["vertices"], 900);
  EXPECT_LT(after["triangles"].get<int>(), before["triangles"].get<int>());
  r = runTinsmith("validate " + trimmed.string());
  EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
  r = runTinsmith("tin --points " + (dir / "grid.xyz").string() + " --trim-hull 0 -o " + trimmed.string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
}

TEST(TinCli, InfoAndQueryDescribeTheTin) {
  const auto in = makePlainInputs("cli-info");
  const fs::path tin = in.dir / "out.tin";
  ASSERT_EQ(runTinsmith("tin -q --points " + in.points.string() + " -o " + tin.string() + " --crs EPSG:26912").exitCode, 0);
  auto r = runTinsmith("info " + tin.string() + " --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["crs"], "EPSG:26912");
  EXPECT_EQ(j["vertices"], 300);
  EXPECT_EQ(j["format_version"], 3);
  EXPECT_GT(j["z_range"][1].get<double>(), j["z_range"][0].get<double>());
  r = runTinsmith("info " + tin.string());
  EXPECT_NE(r.out.find("EPSG:26912"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("300 vertices"), std::string::npos) << r.out;

  // The points lie on a plane, so the TIN reproduces it exactly (to rounding).
  r = runTinsmith("query " + tin.string() + " 431200 4512200 --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto q = nlohmann::json::parse(r.out);
  EXPECT_NEAR(q["z"].get<double>(), plane(200, 200), 1e-6);
  const double slope = std::hypot(0.25, 0.125);
  // (The input z has 6 decimals, so the plane is recovered to about 1e-8.)
  EXPECT_NEAR(q["slope"].get<double>(), slope, 1e-7);
  EXPECT_NEAR(q["normal"][2].get<double>(), 1 / std::sqrt(1 + slope * slope), 1e-7);
  r = runTinsmith("query " + tin.string() + " 431200 4512200");
  EXPECT_EQ(r.exitCode, 0);
  EXPECT_NE(r.out.find("z 1525.000"), std::string::npos) << r.out;

  // Many points at once; one outside is null, not an error.
  const fs::path qp = in.dir / "q.txt";
  writeText(qp, "x y\n431200 4512200\n0 0\n431100 4512300\n");
  r = runTinsmith("query " + tin.string() + " --points " + qp.string() + " --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto many = nlohmann::json::parse(r.out);
  ASSERT_EQ(many.size(), 3u);
  EXPECT_TRUE(many[1]["z"].is_null());
  EXPECT_NEAR(many[2]["z"].get<double>(), plane(100, 300), 1e-6);

  // A single point outside is a clear input error (QueryOfOnePointOutsideExitsThreeAlsoWithJson).
  r = runTinsmith("query " + tin.string() + " 0 0");
  EXPECT_EQ(r.exitCode, 3);
  EXPECT_NE(r.err.find("outside the TIN"), std::string::npos) << r.err;
}

TEST(TinCli, ABreakLineKeepsItsZWhereItPassesThroughASpotHeight) {
  // Regression: in plain mode points and break lines were both of kind
  // Other, so at a break-line vertex on an input point the earlier input —
  // the point — gave the vertex its z and the line was no longer exact.
  const auto dir = test::scratchDir("cli-line-over-point");
  writeText(dir / "p.xyz", "0 0 10\n100 0 10\n100 100 10\n0 100 10\n50 50 99\n");
  writeText(dir / "l.txt", "10 10 20\n50 50 30\n90 90 40\n");
  const fs::path tin = dir / "out.tin";
  auto r = runTinsmith("tin -q --points " + (dir / "p.xyz").string() + " --breaklines " +
                       (dir / "l.txt").string() + " -o " + tin.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = runTinsmith("query " + tin.string() + " 50 50 --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["z"].get<double>(), 30.0) << r.out;
  r = runTinsmith("info " + tin.string() + " --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["kinds"]["breakline"]["constrained_edges"], 2) << r.out;
}

TEST(TinCli, QueryOfOnePointOutsideExitsThreeAlsoWithJson) {
  // Regression: with --json a single point outside the TIN exited 0 (z null)
  // where the text mode exits 3. Now both exit 3; the JSON record is still
  // printed, and a --points run with outside points still exits 0.
  const auto in = makePlainInputs("cli-query-outside");
  const fs::path tin = in.dir / "out.tin";
  ASSERT_EQ(runTinsmith("tin -q --points " + in.points.string() + " -o " + tin.string()).exitCode,
            0);
  auto r = runTinsmith("query " + tin.string() + " 0 0");
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("outside the TIN"), std::string::npos) << r.err;
  r = runTinsmith("query " + tin.string() + " 0 0 --json");
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("outside the TIN"), std::string::npos) << r.err;
  EXPECT_EQ(r.out,
            "{\"x\": 0, \"y\": 0, \"z\": null, \"normal\": null, \"slope\": null, "
            "\"slope_degrees\": null}\n");
  const fs::path qp = in.dir / "q.txt";
  writeText(qp, "0 0\n");
  r = runTinsmith("query " + tin.string() + " --points " + qp.string() + " --json");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)[0]["z"].is_null());
  r = runTinsmith("query " + tin.string() + " --points " + qp.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.out, "0 0 outside\n");
  r = runTinsmith("query --help");
  EXPECT_EQ(r.exitCode, 0);
  EXPECT_NE(r.out.find("exit 3), also with --json"), std::string::npos) << r.out;
}

TEST(TinCli, ExportFormats) {
  const auto in = makePlainInputs("cli-export");
  const fs::path tin = in.dir / "out.tin";
  ASSERT_EQ(runTinsmith("tin -q --points " + in.points.string() + " -o " + tin.string() + " --crs EPSG:26912").exitCode, 0);
  EXPECT_EQ(runTinsmith("export " + tin.string() + " --format ply -o " + (in.dir / "a.ply").string()).exitCode, 0);
  EXPECT_EQ(readFile(in.dir / "a.ply").rfind("ply\nformat ascii 1.0\n", 0), 0u);
  auto r = runTinsmith("export " + tin.string() + " --format tif --cell 10 -o " + (in.dir / "a.tif").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // The cell holding (431205, 4512195) carries the plane's z at its centre.
  r = runCommand("gdalinfo -json " + (in.dir / "a.tif").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto gt = nlohmann::json::parse(r.out)["geoTransform"];
  EXPECT_EQ(gt[1].get<double>(), 10.0);
  EXPECT_EQ(gt[5].get<double>(), -10.0);
  const double col = std::floor((431205 - gt[0].get<double>()) / 10.0);
  const double row = std::floor((gt[3].get<double>() - 4512195) / 10.0);
  const double cx = gt[0].get<double>() + (col + 0.5) * 10.0, cy = gt[3].get<double>() - (row + 0.5) * 10.0;
  r = runCommand("gdallocationinfo -valonly " + (in.dir / "a.tif").string() + " " +
                 std::to_string(static_cast<int>(col)) + " " + std::to_string(static_cast<int>(row)));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NEAR(std::stod(r.out), plane(cx - 431000, cy - 4512000), 1e-3) << r.out;
  r = runTinsmith("export " + tin.string() + " --format exr --cell 10 -o " + (in.dir / "a.exr").string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::file_size(in.dir / "a.exr") > 0);
  r = runTinsmith("export " + tin.string() + " --format exr -o " + (in.dir / "b.exr").string());
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_NE(r.err.find("--cell"), std::string::npos);
  r = runTinsmith("export " + tin.string() + " --format glb -o " + (in.dir / "a.glb").string());
  EXPECT_EQ(r.exitCode, 0) << r.err;  // export_glb_cli_test.cpp checks what it holds
  EXPECT_EQ(readFile(in.dir / "a.glb").rfind("glTF", 0), 0u);
  r = runTinsmith("export " + tin.string() + " --format stl -o " + (in.dir / "a.stl").string());
  EXPECT_EQ(r.exitCode, 2);
  EXPECT_FALSE(fs::exists(in.dir / "b.exr"));
}

// Red Butte: the full config → tin → validate → info → OBJ.
TEST(TinCli, RedButteEndToEnd) {
  const auto dir = test::scratchDir("cli-red-butte");
  const fs::path tin = dir / "red-butte.tin", report = dir / "report.json";
  auto r = runTinsmith("tin " + (kSource / "config/red-butte.toml").string() + " -o " + tin.string() +
                       " --report " + report.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("bridge candidates"), std::string::npos) << r.err;
  r = runTinsmith("validate " + tin.string() + " --json");
  ASSERT_EQ(r.exitCode, 0) << r.out << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["valid"].get<bool>());

  // Break lines are present as constrained edges of every kind.
  r = runTinsmith("info " + tin.string() + " --json");
  ASSERT_EQ(r.exitCode, 0);
  const auto info = nlohmann::json::parse(r.out);
  for (const char* kind : {"contour", "road", "river", "lake", "boundary"})
    EXPECT_GT(info["kinds"][kind]["constrained_edges"].get<int>(), 0) << kind;
  EXPECT_EQ(info["crs"], "EPSG:26912");

  const auto rep = nlohmann::json::parse(readFile(report));
  EXPECT_TRUE(rep["result"]["valid"].get<bool>());
  EXPECT_EQ(rep["layers"].size(), 6u);

  // --validate runs the full validator; the TIN is the same either way.
  const fs::path full = dir / "full.tin";
  r = runTinsmith("tin " + (kSource / "config/red-butte.toml").string() + " -o " + full.string() +
                  " --validate");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("validation: ok (full)"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(full), readFile(tin));
  EXPECT_GT(rep["rivers"]["draped"].get<int>(), 0);
  EXPECT_EQ(rep["roads"]["draped"], 1);
  EXPECT_EQ(rep["lakes"].size(), 1u);
  EXPECT_GT(rep["flat_triangles"]["before"].get<int>(), 100);
  EXPECT_LE(rep["flat_triangles"]["after"].get<int>(), rep["flat_triangles"]["before"].get<int>() / 100);
  EXPECT_GE(rep["triangulation"]["bridge_candidates"].size(), 1u);
  // The lake is flat: its level lies within the z range and is reported.
  EXPECT_GT(rep["lakes"][0]["level_m"].get<double>(), 1500.0);

  r = runTinsmith("export " + tin.string() + " --format obj -o " + (dir / "red-butte.obj").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_GT(fs::file_size(dir / "red-butte.obj"), 1000000u);

  // Same input, same bytes.
  r = runTinsmith("tin -q " + (kSource / "config/red-butte.toml").string() + " -o " + (dir / "again.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(readFile(tin) == readFile(dir / "again.tin"));
}

// The independent checker wants the TIN to tile the convex hull, so it runs on
// the Red Butte layers without the boundary and the lake: contours, spot
// heights, road and streams — every input point a vertex, every contour, road
// and stream segment a chain of edges, all other edges Delaunay.
TEST(TinCli, RedButteWithoutDomainPassesTheIndependentChecker) {
  const auto dir = test::scratchDir("cli-red-butte-check");
  const fs::path data = kShared / "red-butte";
  writeText(dir / "rb.toml", "[project]\ncrs = \"EPSG:26912\"\n"
                             "[[layer]]\npath = \"" + (data / "contours.gpkg").string() +
                                 "\"\nlayer = \"contours\"\nkind = \"contours\"\nz = \"elev\"\n"
                             "[[layer]]\npath = \"" + (data / "spot-heights.csv").string() +
                                 "\"\nkind = \"points\"\ncrs = \"EPSG:26912\"\nz = \"elevation\"\n"
                             "[[layer]]\npath = \"" + (data / "road.geojson").string() + "\"\nkind = \"road\"\n"
                             "[[layer]]\npath = \"" + (data / "streams.geojson").string() + "\"\nkind = \"river\"\n");
  auto r = runTinsmith("tin -q " + (dir / "rb.toml").string() + " -o " + (dir / "rb.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  ASSERT_EQ(runTinsmith("export " + (dir / "rb.tin").string() + " --format obj -o " + (dir / "rb.obj").string()).exitCode, 0);
  r = runCommand("ogr2ogr -f GeoJSON " + (dir / "contours.geojson").string() + " " +
                 (data / "contours.gpkg").string() + " contours");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  // One GeoJSON with every break line; spot heights as "x y z".
  auto lines = nlohmann::json::parse(readFile(dir / "contours.geojson"));
  for (const char* f : {"road.geojson", "streams.geojson"}) {
    const auto more = nlohmann::json::parse(readFile(data / f));
    for (const auto& feature : more["features"]) lines["features"].push_back(feature);
  }
  ASSERT_EQ(lines["features"].size(), 152u + 1u + 23u);
  writeText(dir / "lines.geojson", lines.dump());
  std::string csv = readFile(data / "spot-heights.csv");
  csv = csv.substr(csv.find('\n') + 1);
  for (char& c : csv)
    if (c == ',') c = ' ';
  writeText(dir / "points.xyz", csv);
  // --tol 0.01: the config's snap tolerance (points that close to a break-line
  // vertex are merged into it).
  r = runCommand("python3 " + kChecker + " " + (dir / "rb.obj").string() + " " + (dir / "points.xyz").string() +
                 " " + (dir / "lines.geojson").string() + " --tol 0.01");
  EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
  EXPECT_EQ(r.out.rfind("ok", 0), 0u) << r.out;
}

// --- bad input: a clear error, the documented exit code, no output ---------

struct BadCase {
  const char* name;
  std::string args;  ///< after "tin", before "-o"
  int exitCode;
  const char* mentions;
};

TEST(TinCli, BadInputFailsClearlyAndLeavesNoFile) {
  const auto in = makePlainInputs("cli-bad");
  const fs::path& d = in.dir;
  writeText(d / "nan.xyz", "1 2 3\n4 5 6\n7 nan 9\n");
  writeText(d / "words.xyz", "1 2 3\n4 five 6\n");
  writeText(d / "collinear.xyz", "0 0 1\n1 1 2\n2 2 3\n3 3 4\n");
  writeText(d / "single.txt", "1 2 3\n4 5 6\n\n7 8 9\n");
  writeText(d / "flat.geojson",
            "{\"type\": \"FeatureCollection\", \"features\": [{\"type\": \"Feature\", \"properties\": {}, "
            "\"geometry\": {\"type\": \"LineString\", \"coordinates\": [[431000, 4512000], [431100, 4512100]]}}]}");
  writeText(d / "unknown-key.toml", "[project]\ncrs = \"EPSG:26912\"\ncolour = \"red\"\n");
  writeText(d / "no-layers.toml", "[project]\ncrs = \"EPSG:26912\"\n");
  const std::string pts = in.points.string();
  const std::vector<BadCase> cases = {
      {"missing points file", "--points " + (d / "none.xyz").string(), 3, "none.xyz"},
      {"NaN coordinate", "--points " + (d / "nan.xyz").string(), 3, "nan.xyz"},
      {"non-numeric field", "--points " + (d / "words.xyz").string(), 3, "line 2"},
      {"collinear points", "--points " + (d / "collinear.xyz").string(), 4, "collinear"},
      {"one-vertex polyline", "--points " + pts + " --breaklines " + (d / "single.txt").string(), 3, "line 4"},
      {"2D GeoJSON break line", "--points " + pts + " --breaklines " + (d / "flat.geojson").string(), 3, "no z"},
      {"missing config", (d / "none.toml").string(), 3, "none.toml"},
      {"unknown config key", (d / "unknown-key.toml").string(), 3, "colour"},
      {"config and points", (d / "no-layers.toml").string() + " --points " + pts, 2, "not both"},
      {"nothing to do", "", 2, "nothing to triangulate"},
  };
  for (const auto& c : cases) {
    const fs::path out = d / "out" / (std::string(c.name) + ".tin");
    fs::create_directories(out.parent_path());
    const auto r = runTinsmith("tin " + c.args + " -o \"" + out.string() + "\"");
    EXPECT_EQ(r.exitCode, c.exitCode) << c.name << ": " << r.err;
    EXPECT_EQ(r.err.rfind("ERROR: ", 0), 0u) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.name << ": " << r.err;
    EXPECT_EQ(test::filesIn(out.parent_path()), 0u) << c.name << " left a file behind";
  }
}

// --block-points: the bowed grid built block by block — every point a
// vertex, the hull's slivers gone by the circumradius, a TIN the validator
// (Delaunay property included) accepts — and what it refuses.
TEST(TinCli, ByBlocksEveryPointStaysAndTheValidatorAccepts) {
  const fs::path dir = test::scratchDir("cli-blocks");
  std::string pts = "# a bowed grid\nx y z\n";
  char buf[128];
  for (int j = 0; j < 40; ++j) {
    const double bow = 300 * std::sin(3.14159265358979 * j / 39.0);
    for (int i = 0; i < 40; ++i) {
      std::snprintf(buf, sizeof buf, "%.3f %.3f %.3f\n", 431000 + 90.0 * i + bow,
                    4512000 + 90.0 * j, 1500.0 + i + (j % 3));
      pts += buf;
    }
  }
  writeText(dir / "grid.xyz", pts);
  const fs::path tin = dir / "blocks.tin", report = dir / "blocks.json";
  auto r = runTinsmith("tin --points " + (dir / "grid.xyz").string() +
                       " --crs EPSG:26912 --block-points 100 --max-circumradius 120 --report " +
                       report.string() + " -o " + tin.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("TIN built by blocks"), std::string::npos) << r.err;
  const auto json = nlohmann::json::parse(readFile(report));
  EXPECT_GT(json["blocks"]["withPoints"].get<int>(), 9) << json.dump();
  EXPECT_EQ(json["vertices"], 1600);
  EXPECT_GT(json["leftOut"].get<int>(), 0) << "the bow's slivers";
  const auto info = nlohmann::json::parse(runTinsmith("info " + tin.string() + " --json").out);
  EXPECT_EQ(info["vertices"], 1600);
  EXPECT_EQ(info["triangles"], json["triangles"]);
  // Cells of 90 m (circumradius 63.6 m) all kept: 2 × 39 × 39 triangles.
  EXPECT_EQ(info["triangles"], 2 * 39 * 39);
  r = runTinsmith("validate " + tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
  // No scratch left beside the output.
  EXPECT_EQ(test::filesIn(dir), 3u);

  const std::string points = " --points " + (dir / "grid.xyz").string();
  const std::vector<BadCase> cases = {
      {"with break lines",
       points + " --breaklines " + (dir / "grid.xyz").string() + " --block-points 100", 2,
       "--points only"},
      {"with --trim-hull", points + " --block-points 100 --trim-hull 200", 2, "--max-circumradius"},
      {"radius alone", points + " --max-circumradius 100", 2, "--block-points"},
      {"radius 0", points + " --block-points 100 --max-circumradius 0", 2, "greater than 0"},
      {"tiny blocks", points + " --block-points 3", 2, "block-points"},
      {"radius under every cell", points + " --block-points 100 --max-circumradius 40", 4,
       "circumradius"},
  };
  for (const auto& c : cases) {
    const fs::path out = dir / "out" / (std::string(c.name) + ".tin");
    fs::create_directories(out.parent_path());
    r = runTinsmith("tin" + c.args + " -o \"" + out.string() + "\"");
    EXPECT_EQ(r.exitCode, c.exitCode) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.name << ": " << r.err;
    EXPECT_EQ(test::filesIn(out.parent_path()), 0u) << c.name << " left a file behind";
  }
  // A bad line deep in a file read in chunks is named by its line.
  pts += "431000 4512000 x\n";
  writeText(dir / "bad.xyz", pts);
  r = runTinsmith("tin --points " + (dir / "bad.xyz").string() + " --block-points 100 -o " +
                  (dir / "out" / "bad.tin").string());
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("bad.xyz"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 1603"), std::string::npos) << r.err;
  EXPECT_EQ(test::filesIn(dir / "out"), 0u);

  // A DEM raster, read in strips by blocks and whole at once: the same
  // vertices (every valid cell).
  const fs::path dem = kShared / "red-butte" / "dem.tif", rasters = dir / "raster";
  fs::create_directories(rasters);
  r = runTinsmith("tin -q --points " + dem.string() + " --crs EPSG:26912 --block-points 4000 " +
                  "--max-circumradius 80 -o " + (rasters / "blocks.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  ASSERT_EQ(runTinsmith("tin -q --points " + dem.string() + " --crs EPSG:26912 -o " +
                        (rasters / "whole.tin").string())
                .exitCode,
            0);
  const auto blocks =
      nlohmann::json::parse(runTinsmith("info --json " + (rasters / "blocks.tin").string()).out);
  const auto whole =
      nlohmann::json::parse(runTinsmith("info --json " + (rasters / "whole.tin").string()).out);
  EXPECT_EQ(blocks["vertices"], 31732);
  EXPECT_EQ(blocks["vertices"], whole["vertices"]);
  EXPECT_EQ(runTinsmith("validate " + (rasters / "blocks.tin").string()).exitCode, 0);
}

TEST(TinCli, AFailedRunKeepsTheOldOutputAndAMissingDirectoryIsAnIoError) {
  const auto in = makePlainInputs("cli-keep");
  const fs::path out = in.dir / "keep.tin";
  writeText(out, "previous");
  writeText(in.dir / "bad.xyz", "1 2 x\n");
  auto r = runTinsmith("tin --points " + (in.dir / "bad.xyz").string() + " -o " + out.string());
  EXPECT_EQ(r.exitCode, 3);
  EXPECT_EQ(readFile(out), "previous");
  const auto before = test::filesIn(in.dir);
  r = runTinsmith("tin --points " + in.points.string() + " -o " + (in.dir / "no/such/dir/x.tin").string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  r = runTinsmith("tin --points " + in.points.string() + " -o " + out.string() + " --report " +
                  (in.dir / "nope/r.json").string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_EQ(readFile(out), "previous");
  EXPECT_EQ(test::filesIn(in.dir), before);
}

// A .tin written by hand from the documented layout (ingest/tinfile/tin_file.hpp):
// an independent check of the format, and a way to hand `validate` a file
// whose bytes are sound but whose mesh is not.
std::uint32_t crc32(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char b : bytes) {
    crc ^= b;
    for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  return ~crc;
}

template <class T>
void put(std::string& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));  // the test machine is little-endian, like the format
  out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

std::string handMadeTin(const std::vector<std::array<double, 3>>& v,
                        const std::vector<std::array<std::uint32_t, 3>>& t) {
  std::string payload;
  put<std::uint32_t>(payload, 0);  // no CRS
  put<std::uint64_t>(payload, v.size());
  for (const auto& p : v)
    for (double c : p) put(payload, c);
  put<std::uint64_t>(payload, t.size());
  for (const auto& tri : t)
    for (auto i : tri) put(payload, i);
  put<std::uint64_t>(payload, 0);  // features
  put<std::uint64_t>(payload, 0);  // constrained edges
  std::string h("\x89TIN\r\n\x1a\n", 8);
  put<std::uint32_t>(h, 1);
  put<std::uint32_t>(h, 0);
  put<std::uint64_t>(h, payload.size());
  put<std::uint32_t>(h, crc32(payload));
  put<std::uint32_t>(h, crc32(h));
  return h + payload;
}

TEST(TinCli, ValidateExitsOneAndListsProblemsForABrokenMesh) {
  const auto dir = test::scratchDir("cli-validate");
  const std::vector<std::array<double, 3>> v = {{0, 0, 1}, {10, 0, 2}, {10, 10, 3}, {0, 10, 4}};
  writeText(dir / "good.tin", handMadeTin(v, {{{0, 1, 2}}, {{0, 2, 3}}}));
  auto r = runTinsmith("validate " + (dir / "good.tin").string());
  EXPECT_EQ(r.exitCode, 0) << r.out << r.err;
  // Second triangle clockwise.
  writeText(dir / "bad.tin", handMadeTin(v, {{{0, 1, 2}}, {{0, 3, 2}}}));
  r = runTinsmith("validate " + (dir / "bad.tin").string());
  EXPECT_EQ(r.exitCode, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("INVALID"), std::string::npos) << r.out;
  r = runTinsmith("validate " + (dir / "bad.tin").string() + " --json");
  EXPECT_EQ(r.exitCode, 1);
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["valid"].get<bool>());
  EXPECT_FALSE(j["problems"].empty());
  // Damaged bytes are an input error naming the file, not a failed check.
  std::string damaged = readFile(dir / "good.tin");
  damaged[40] ^= 0x01;
  writeText(dir / "damaged.tin", damaged);
  r = runTinsmith("validate " + (dir / "damaged.tin").string());
  EXPECT_EQ(r.exitCode, 3);
  EXPECT_NE(r.err.find("damaged.tin"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("checksum"), std::string::npos) << r.err;
  writeText(dir / "text.tin", "hello");
  r = runTinsmith("info " + (dir / "text.tin").string());
  EXPECT_EQ(r.exitCode, 3);
  EXPECT_NE(r.err.find("not a .tin file"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace tinsmith

namespace tinsmith {
namespace {

TEST(TinCli, StrictMakesContourCrossingsFatalAndWritesNothing) {
  const auto dir = test::scratchDir("cli-strict");
  const std::string config = (kSource / "config/chatham.toml").string();
  auto r = runTinsmith("tin " + config + " -o " + (dir / "c.tin").string() + " --strict");
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("cross"), std::string::npos) << r.err;
  EXPECT_EQ(test::filesIn(dir), 0u);
  // Without --strict the same crossings are reported and the TIN is built.
  r = runTinsmith("tin " + config + " -o " + (dir / "c.tin").string() + " --report " + (dir / "r.json").string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("data errors:"), std::string::npos) << r.err;
  EXPECT_FALSE(nlohmann::json::parse(readFile(dir / "r.json"))["data_errors"].empty());
}

TEST(TinCli, ProgressBarsOnlyOnATerminal) {
  const auto in = makePlainInputs("cli-progress");
  const std::string tin = "tin --points " + in.points.string() + " -o " + (in.dir / "p.tin").string();
  auto r = runTinsmith(tin);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << "progress drawn on a non-terminal";
  if (runCommand("command -v script").exitCode != 0) GTEST_SKIP() << "no `script` to make a terminal";
  // `script` runs the command on a pseudo-terminal; its output is the terminal's.
  r = runCommand("script -qec \"" + std::string(TINSMITH_BINARY) + " " + tin + "\" /dev/null");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("\r\033[Kbuilders.tin"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("100%"), std::string::npos) << r.out;
}

TEST(TinCli, APlainRunRefusesACrsThatIsNotInMetres) {
  const auto dir = test::scratchDir("tin-cli-feet");
  for (const char* crs : {"EPSG:2227", "EPSG:4326"}) {
    const auto r = runTinsmith(
        std::string("tin --points 'synthetic:grid?nx=5&ny=5&spacing=10&x0=6000000&y0=2000000' "
                    "--crs ") +
        crs + " -q -o " + (dir / "t.tin").string());
    EXPECT_EQ(r.exitCode, 3) << crs << ": " << r.err;
    EXPECT_NE(r.err.find(crs), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("metres"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "t.tin"));
  }
}

}  // namespace
}  // namespace tinsmith
