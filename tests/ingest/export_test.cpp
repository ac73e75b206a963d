// OBJ/PLY export: exact round trip of every coordinate, deterministic text,
// atomic output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <sstream>

#include "core/base/error.hpp"
#include "ingest/export/mesh_export.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

TinData randomTin(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  TinData tin;
  tin.crs = "EPSG:3793";
  for (int i = 0; i < 200; ++i)
    tin.vertices.push_back({1.8e6 + u(rng) * 1e4, 5.1e6 + u(rng) * 1e4, u(rng) * 300 - 5});
  tin.vertices.push_back({0.1, 1e-310, -0.0});  // denormal and negative zero
  tin.vertices.push_back({1e300, -1.7976931348623157e308, 5e-324});
  for (std::uint32_t i = 0; i + 2 < tin.vertices.size(); i += 3) tin.triangles.push_back({i, i + 1, i + 2});
  return tin;
}

TEST(MeshExport, G17MatchesPrintf) {
  for (double v : {0.0, -0.0, 1.0, 0.1, 1.0 / 3.0, 4512000.0000001, 1e-310, 1e300, -2.5e-7}) {
    char expected[64];
    std::snprintf(expected, sizeof expected, "%.17g", v);
    std::string got;
    appendG17(got, v);
    EXPECT_EQ(got, expected);
  }
}

TEST(MeshExport, ObjCoordinatesRoundTripExactly) {
  const TinData tin = randomTin(7);
  const std::string text = objText(tin);
  std::istringstream in(text);
  std::string line;
  std::size_t v = 0, f = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      double x, y, z;
      ASSERT_EQ(std::sscanf(line.c_str(), "v %lf %lf %lf", &x, &y, &z), 3);
      ASSERT_LT(v, tin.vertices.size());
      EXPECT_EQ(std::bit_cast<std::uint64_t>(x), std::bit_cast<std::uint64_t>(tin.vertices[v].x));
      EXPECT_EQ(std::bit_cast<std::uint64_t>(y), std::bit_cast<std::uint64_t>(tin.vertices[v].y));
      EXPECT_EQ(std::bit_cast<std::uint64_t>(z), std::bit_cast<std::uint64_t>(tin.vertices[v].z));
      ++v;
    } else if (line.rfind("f ", 0) == 0) {
      unsigned a, b, c;
      ASSERT_EQ(std::sscanf(line.c_str(), "f %u %u %u", &a, &b, &c), 3);
      EXPECT_EQ(a - 1, tin.triangles[f][0]);
      EXPECT_EQ(b - 1, tin.triangles[f][1]);
      EXPECT_EQ(c - 1, tin.triangles[f][2]);
      ++f;
    } else {
      EXPECT_EQ(line.rfind("#", 0), 0u) << line;
    }
  }
  EXPECT_EQ(v, tin.vertices.size());
  EXPECT_EQ(f, tin.triangles.size());
  EXPECT_NE(text.find("# crs: EPSG:3793"), std::string::npos);
}

TEST(MeshExport, PlyHeaderAndBodyRoundTrip) {
  const TinData tin = randomTin(11);
  const std::string text = plyText(tin);
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "ply");
  bool sawVertexCount = false;
  while (std::getline(in, line) && line != "end_header")
    if (line == "element vertex " + std::to_string(tin.vertices.size())) sawVertexCount = true;
  EXPECT_TRUE(sawVertexCount);
  for (const auto& p : tin.vertices) {
    double x, y, z;
    ASSERT_TRUE(in >> x >> y >> z);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(x), std::bit_cast<std::uint64_t>(p.x));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(y), std::bit_cast<std::uint64_t>(p.y));
    EXPECT_EQ(std::bit_cast<std::uint64_t>(z), std::bit_cast<std::uint64_t>(p.z));
  }
  for (const auto& t : tin.triangles) {
    unsigned n, a, b, c;
    ASSERT_TRUE(in >> n >> a >> b >> c);
    EXPECT_EQ(n, 3u);
    EXPECT_EQ((TinData::Triangle{a, b, c}), t);
  }
  std::string rest;
  EXPECT_FALSE(in >> rest);
}

TEST(MeshExport, FilesMatchTextAndAreDeterministic) {
  const auto dir = test::scratchDir("export-files");
  const TinData tin = randomTin(3);
  writeObj(dir / "a.obj", tin);
  writePly(dir / "a.ply", tin);
  EXPECT_EQ(test::readFile(dir / "a.obj"), objText(tin));
  EXPECT_EQ(test::readFile(dir / "a.ply"), plyText(tin));
  EXPECT_EQ(objText(tin), objText(randomTin(3)));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), {}), 2);
}

TEST(MeshExport, MultiLineWktCrsStaysOneCommentLine) {
  TinData tin;
  tin.crs = "PROJCS[\"x\",\n  GEOGCS[\"y\"]]";
  EXPECT_NE(objText(tin).find("# crs: PROJCS[\"x\",   GEOGCS[\"y\"]]\n"), std::string::npos);
}

TEST(MeshExport, MissingDirectoryIsAnIoErrorAndNoFile) {
  const auto dir = test::scratchDir("export-io");
  try {
    writeObj(dir / "nope" / "a.obj", randomTin(1));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_NE(std::string(e.what()).find("a.obj"), std::string::npos);
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace tinsmith::ingest
