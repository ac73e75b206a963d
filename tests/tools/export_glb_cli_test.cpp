// `tinsmith export --format glb` driven as a user would, its output read back
// with the project's own decoder (core/encode/glb_decode.cpp) and placed with
// GeographicLib's UTM and geocentric conversions, independently of the PROJ
// path the exporter takes: every TIN vertex recovered within the declared
// bound in both compressions and both frames, the triangles kept with their
// winding, 32-bit indices past 65 535 vertices, and errors that name the
// file and leave any old output as it was.
#include <gtest/gtest.h>

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/encode/glb.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith {
namespace {

namespace fs = std::filesystem;
using test::readFile;
using test::runTinsmith;

const std::string kTinsmith = TINSMITH_BINARY;
// EPSG:32612, WGS 84 / UTM 12N: PROJ only projects (no datum shift), so
// GeographicLib's UTM is an independent check of it to nanometres.
constexpr int kUtmZone = 12;

// A hill (slopes up to about 7°) of `side` × `side` points jittered off a
// 2 m grid at UTM 12N coordinates, as a .tin with (or without) a CRS.
fs::path hillTin(const fs::path& dir, int side, bool withCrs = true) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  std::string text;
  char buf[128];
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      // The outer ring stays on the grid: jittered, its near-collinear points
      // would make hull slivers, steep across their width, whose area
      // outweighs the hill's triangles in the normals at their corners.
      const bool ring = i == 0 || j == 0 || i == side - 1 || j == side - 1;
      const double dx = jitter(rng), dy = jitter(rng);
      const double x = 2.0 * i + (ring ? 0.0 : dx), y = 2.0 * j + (ring ? 0.0 : dy);
      const double z = 1600.0 + 0.1 * side *
                                    std::exp(-((x - side) * (x - side) + (y - side) * (y - side)) /
                                             (0.5 * side * side));
      std::snprintf(buf, sizeof buf, "%.4f %.4f %.4f\n", 433000 + x, 4515000 + y, z);
      text += buf;
    }
  }
  const fs::path points = dir / "hill.xyz", tin = dir / (withCrs ? "hill.tin" : "nocrs.tin");
  std::ofstream(points, std::ios::binary) << text;
  const auto r = runTinsmith("tin -q --points " + points.string() + " -o " + tin.string() +
                             (withCrs ? " --crs EPSG:32612" : ""));
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return tin;
}

encode::DecodedGlb decodeFile(const fs::path& glb) {
  return encode::decodeGlb(readFile(glb), glb.string());
}

nlohmann::json extrasOf(const encode::DecodedGlb& g) {
  return nlohmann::json::parse(g.assetExtras).at("tinsmith");
}

// The glTF JSON chunk of a .glb (its accessors say the index width).
nlohmann::json gltfJson(const std::string& bytes) {
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return nlohmann::json::parse(bytes.substr(20, length));
}

// Column-major 4×4 matrix times a point.
Point3 apply(const encode::Matrix4& m, const std::array<float, 3>& p) {
  const double x = p[0], y = p[1], z = p[2];
  return {m[0] * x + m[4] * y + m[8] * z + m[12], m[1] * x + m[5] * y + m[9] * z + m[13],
          m[2] * x + m[6] * y + m[10] * z + m[14]};
}

// A decoded position in the ECEF frame: the root node's matrix, then 3D
// Tiles' (and CesiumJS's) y-up → z-up turn (x, y, z) ↦ (x, −z, y).
Point3 toEcef(const encode::DecodedGlb& g, const std::array<float, 3>& p) {
  const Point3 q = apply(g.rootMatrix, p);
  return {q.x, -q.z, q.y};
}

// An ECEF point back in UTM 12N metres and its ellipsoidal height.
Point3 ecefToUtm(const Point3& e) {
  double lat = 0, lon = 0, h = 0, x = 0, y = 0, gamma = 0, k = 0;
  GeographicLib::Geocentric::WGS84().Reverse(e.x, e.y, e.z, lat, lon, h);
  int zone = 0;
  bool north = false;
  GeographicLib::UTMUPS::Forward(lat, lon, zone, north, x, y, gamma, k, kUtmZone);
  EXPECT_EQ(zone, kUtmZone);
  EXPECT_TRUE(north);
  return {x, y, h};
}

double distance(const Point3& a, const Point3& b) {
  return std::hypot(a.x - b.x, a.y - b.y, a.z - b.z);
}

// Matches decoded positions (already in the TIN's x, y, z) to TIN vertices by
// nearest x, y: every TIN vertex must have a decoded position within
// `bound` of it and every decoded position must be one (Draco reorders them).
// Returns the TIN vertex of each decoded position; records the largest error.
std::vector<std::uint32_t> matchVertices(const TinData& tin, const std::vector<Point3>& decoded,
                                         double bound, double& worst) {
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> grid;  // 1 m cells of TIN vertices
  const auto key = [](double x, double y) {
    return (static_cast<std::int64_t>(std::floor(x)) << 32) ^
           static_cast<std::int64_t>(std::floor(y));
  };
  for (std::uint32_t v = 0; v < tin.vertices.size(); ++v)
    grid[key(tin.vertices[v].x, tin.vertices[v].y)].push_back(v);
  std::vector<std::uint32_t> match(decoded.size());
  std::vector<char> seen(tin.vertices.size(), 0);
  worst = 0;
  for (std::size_t i = 0; i < decoded.size(); ++i) {
    const Point3& p = decoded[i];
    double best = HUGE_VAL;
    std::uint32_t at = 0;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        const auto cell = grid.find(key(p.x + dx, p.y + dy));
        if (cell == grid.end()) continue;
        for (auto v : cell->second) {
          const double d = distance(p, tin.vertices[v]);
          if (d < best) best = d, at = v;
        }
      }
    }
    EXPECT_LE(best, bound) << "decoded position " << i;
    worst = std::max(worst, best);
    match[i] = at;
    seen[at] = 1;
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(tin.vertices.size()))
      << "some TIN vertex has no decoded position";
  return match;
}

// Every decoded triangle is a TIN triangle with the same winding, and each
// TIN triangle is there once.
void expectSameTriangles(const TinData& tin, const std::vector<std::uint32_t>& indices,
                         const std::vector<std::uint32_t>& match) {
  ASSERT_EQ(indices.size(), 3 * tin.triangles.size());
  const auto rotated = [](std::array<std::uint32_t, 3> t) {  // smallest index first, order kept
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  std::set<std::array<std::uint32_t, 3>> expected;
  for (const auto& t : tin.triangles) expected.insert(rotated(t));
  std::set<std::array<std::uint32_t, 3>> got;
  for (std::size_t i = 0; i < indices.size(); i += 3)
    got.insert(rotated({match[indices[i]], match[indices[i + 1]], match[indices[i + 2]]}));
  EXPECT_EQ(got.size(), tin.triangles.size());
  EXPECT_TRUE(got == expected) << "the decoded triangles are not the TIN's, winding kept";
}

// Decodes an ecef-frame export and holds it to the TIN.
void checkEcefExport(const fs::path& glb, const TinData& tin, bool draco) {
  const auto g = decodeFile(glb);
  EXPECT_EQ(g.draco, draco);
  const auto extras = extrasOf(g);
  EXPECT_EQ(extras.at("frame"), "ecef");
  EXPECT_EQ(extras.at("crs"), "EPSG:32612");
  EXPECT_EQ(extras.at("vertices"), tin.vertices.size());
  EXPECT_EQ(extras.at("triangles"), tin.triangles.size());
  const double bound = extras.at("positionErrorBound").get<double>();
  EXPECT_GT(bound, 0.0);
  if (draco) {
    EXPECT_EQ(bound, 0.01);  // the default
  } else {
    EXPECT_LT(bound, 1e-4);  // float32 alone: micrometres a few hundred metres out
  }
  EXPECT_EQ(g.mesh.positions.size(), tin.vertices.size());
  std::vector<Point3> utm;
  for (const auto& p : g.mesh.positions) utm.push_back(ecefToUtm(toEcef(g, p)));
  double worst = 0;
  // The bound is in ECEF metres; UTM's scale factor (1 ± 4e-4 here) and the
  // reverse conversions add micrometres.
  const auto match = matchVertices(tin, utm, bound * 1.001 + 1e-6, worst);
  expectSameTriangles(tin, g.mesh.indices, match);
  // Normals point up, away from the Earth's centre.
  for (std::size_t i = 0; i < g.mesh.normals.size(); ++i) {
    const Point3 e = toEcef(g, g.mesh.positions[i]);
    const encode::Matrix4& m = g.rootMatrix;
    const auto& n = g.mesh.normals[i];
    const Point3 q{m[0] * n[0] + m[4] * n[1] + m[8] * n[2], m[1] * n[0] + m[5] * n[1] + m[9] * n[2],
                   m[2] * n[0] + m[6] * n[1] + m[10] * n[2]};
    const Point3 ne{q.x, -q.z, q.y};
    EXPECT_GT((ne.x * e.x + ne.y * e.y + ne.z * e.z) / std::hypot(e.x, e.y, e.z), 0.9) << i;
  }
}

TEST(ExportGlb, DracoAndPlainHoldEveryVertexWithinTheDeclaredBoundOnTheGlobe) {
  const auto dir = test::scratchDir("export-glb-ecef");
  const auto tin = hillTin(dir, 40);
  const TinData data = ingest::readTinFile(tin);
  for (const bool draco : {true, false}) {
    const fs::path glb = dir / (draco ? "draco.glb" : "plain.glb");
    const auto r = runTinsmith("export " + tin.string() + " --format glb -o " + glb.string() +
                               (draco ? "" : " --compression none"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find(std::to_string(fs::file_size(glb)) + " bytes"), std::string::npos)
        << r.err;
    checkEcefExport(glb, data, draco);
  }
  // Deterministic: the same TIN and options give the same bytes.
  const fs::path again = dir / "again.glb";
  ASSERT_EQ(runTinsmith("export " + tin.string() + " --format glb -o " + again.string()).exitCode,
            0);
  EXPECT_EQ(readFile(again), readFile(dir / "draco.glb"));
}

TEST(ExportGlb, MaxPositionErrorBoundsDracosRounding) {
  const auto dir = test::scratchDir("export-glb-bound");
  const auto tin = hillTin(dir, 30);
  const TinData data = ingest::readTinFile(tin);
  const fs::path coarse = dir / "coarse.glb", fine = dir / "fine.glb";
  ASSERT_EQ(runTinsmith("export " + tin.string() + " --format glb --max-position-error 0.05 -o " +
                        coarse.string())
                .exitCode,
            0);
  ASSERT_EQ(runTinsmith("export " + tin.string() + " --format glb --max-position-error 0.0001 -o " +
                        fine.string())
                .exitCode,
            0);
  const auto c = decodeFile(coarse), f = decodeFile(fine);
  EXPECT_EQ(extrasOf(c).at("positionErrorBound").get<double>(), 0.05);
  EXPECT_EQ(extrasOf(f).at("positionErrorBound").get<double>(), 0.0001);
  double worstCoarse = 0, worstFine = 0;
  std::vector<Point3> utm;
  for (const auto& p : c.mesh.positions) utm.push_back(ecefToUtm(toEcef(c, p)));
  matchVertices(data, utm, 0.05 * 1.001, worstCoarse);
  utm.clear();
  for (const auto& p : f.mesh.positions) utm.push_back(ecefToUtm(toEcef(f, p)));
  matchVertices(data, utm, 0.0001 * 1.001 + 1e-6, worstFine);
  EXPECT_GT(worstCoarse, 0.001);  // the coarse bound is used, not wasted
  EXPECT_LT(fs::file_size(coarse), fs::file_size(fine));
  // Tighter than float32 positions 60 m from the centre can hold: refused.
  const fs::path tight = dir / "tight.glb";
  const auto r = runTinsmith("export " + tin.string() +
                             " --format glb --max-position-error 1e-7 -o " + tight.string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("--max-position-error"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tight));
}

TEST(ExportGlb, Egm96HeightsAreRaisedByTheGeoidAsTheTilesAre) {
  const auto dir = test::scratchDir("export-glb-geoid");
  const auto tin = hillTin(dir, 20);
  const TinData data = ingest::readTinFile(tin);
  const fs::path glb = dir / "geoid.glb";
  const auto r =
      runTinsmith("export " + tin.string() + " --format glb --geoid egm96 -o " + glb.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto g = decodeFile(glb);
  EXPECT_EQ(extrasOf(g).at("geoid"), "egm96");
  // Ellipsoidal height = EGM96 height + N; N is about −17 m in north-east Utah
  // and all but constant over 40 m.
  std::vector<Point3> utm;
  for (const auto& p : g.mesh.positions) utm.push_back(ecefToUtm(toEcef(g, p)));
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const auto& p : utm) {
    double nearest = HUGE_VAL, dz = 0;
    for (const auto& v : data.vertices) {
      const double d = std::hypot(p.x - v.x, p.y - v.y);
      if (d < nearest) nearest = d, dz = p.z - v.z;
    }
    ASSERT_LT(nearest, 0.01);
    lo = std::min(lo, dz);
    hi = std::max(hi, dz);
  }
  EXPECT_GT(lo, -25.0);
  EXPECT_LT(hi, -10.0);
  EXPECT_LT(hi - lo, 0.05);
}

TEST(ExportGlb, LocalFrameIsTheTinMinusAWholeMetreOffsetWithYUp) {
  const auto dir = test::scratchDir("export-glb-local");
  const auto tin = hillTin(dir, 30, /*withCrs=*/false);  // the local frame needs no CRS
  const TinData data = ingest::readTinFile(tin);
  for (const bool draco : {true, false}) {
    const fs::path glb = dir / (draco ? "draco.glb" : "plain.glb");
    const auto r = runTinsmith("export " + tin.string() + " --format glb --frame local -o " +
                               glb.string() + (draco ? "" : " --compression none"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto g = decodeFile(glb);
    const auto extras = extrasOf(g);
    EXPECT_EQ(extras.at("frame"), "local");
    const auto offset = extras.at("offset").get<std::array<double, 3>>();
    for (double o : offset) EXPECT_EQ(o, std::round(o));
    EXPECT_NEAR(offset[0], 433030, 1.0);
    EXPECT_NEAR(offset[1], 4515030, 1.0);
    // The node only turns z-up into glTF's y-up: no translation, glTF y is
    // the height above the offset, glTF z is minus the northing.
    const encode::Matrix4 turn{1, 0, 0, 0, 0, 0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1};
    EXPECT_EQ(g.rootMatrix, turn);
    std::vector<Point3> project;
    for (const auto& p : g.mesh.positions) {
      const Point3 yUp = apply(g.rootMatrix, p);
      project.push_back({yUp.x + offset[0], -yUp.z + offset[1], yUp.y + offset[2]});
    }
    double worst = 0;
    const auto match =
        matchVertices(data, project, extras.at("positionErrorBound").get<double>(), worst);
    expectSameTriangles(data, g.mesh.indices, match);
    for (const auto& n : g.mesh.normals) EXPECT_GT(n[2], 0.5);  // up before the turn
  }
}

TEST(ExportGlb, ATinOver65535VerticesGets32BitIndices) {
  const auto dir = test::scratchDir("export-glb-big");
  const auto tin = hillTin(dir, 260);  // 67 600 vertices
  const TinData data = ingest::readTinFile(tin);
  ASSERT_GT(data.vertices.size(), 65535u);
  for (const bool draco : {true, false}) {
    const fs::path glb = dir / (draco ? "draco.glb" : "plain.glb");
    const auto r = runTinsmith("export " + tin.string() + " --format glb -o " + glb.string() +
                               (draco ? "" : " --compression none"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string bytes = readFile(glb);
    const auto json = gltfJson(bytes);
    const auto& indices =
        json["accessors"][json["meshes"][0]["primitives"][0]["indices"].get<int>()];
    EXPECT_EQ(indices["componentType"], 5125);  // UNSIGNED_INT
    checkEcefExport(glb, data, draco);
  }
}

TEST(ExportGlb, ErrorsNameTheFileAndLeaveTheOldOutputAsItWas) {
  const auto dir = test::scratchDir("export-glb-errors");
  const auto tin = hillTin(dir, 12);
  const auto noCrs = hillTin(dir, 12, /*withCrs=*/false);
  const fs::path out = dir / "x.glb";
  std::ofstream(out, std::ios::binary) << "the old file";
  const std::size_t entries = test::filesIn(dir);
  const auto unchanged = [&] {
    EXPECT_EQ(readFile(out), "the old file");
    EXPECT_EQ(test::filesIn(dir), entries) << "a temp file was left behind";
  };
  const std::string to = " --format glb -o " + out.string();

  auto r = runTinsmith("export " + (dir / "missing.tin").string() + to);
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("missing.tin"), std::string::npos) << r.err;
  unchanged();

  r = runTinsmith("export " + noCrs.string() + to);
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("nocrs.tin"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no CRS"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--frame local"), std::string::npos) << r.err;
  unchanged();

  // A file-size limit: the write fails (EFBIG), the old file stays.
  r = test::runCommand("ulimit -f 1; exec " + kTinsmith + " export " + tin.string() + to +
                       " --compression none");
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_NE(r.err.find(out.string()), std::string::npos) << r.err;
  unchanged();

  r = runTinsmith("export " + tin.string() + " --format glb -o " +
                  (dir / "no/such/x.glb").string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_NE(r.err.find("no/such/x.glb"), std::string::npos) << r.err;
  r = runTinsmith("export " + tin.string() + " --format glb -o " + dir.string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  unchanged();

  for (const char* bad :
       {"--frame enu", "--compression lzma", "--max-position-error 0", "--max-position-error -1",
        "--geoid egm2008", "--frame local --geoid egm96"}) {
    r = runTinsmith("export " + tin.string() + to + " " + bad);
    EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.err;
    unchanged();
  }
  r = runTinsmith("export " + tin.string() + " --format obj --frame local -o " +
                  (dir / "a.obj").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("--format glb"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "a.obj"));

  // A good export replaces the old file.
  r = runTinsmith("export " + tin.string() + to);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readFile(out).substr(0, 4), "glTF");
  EXPECT_EQ(test::filesIn(dir), entries);
}

TEST(ExportGlb, HelpDocumentsTheGlbOptions) {
  const auto r = runTinsmith("export --help");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  for (const char* o :
       {"--compression", "--frame", "--max-position-error", "--geoid", "0.01", "y up"})
    EXPECT_NE(r.out.find(o), std::string::npos) << o << "\n" << r.out;
}

}  // namespace
}  // namespace tinsmith
