// A tile's surface as a shard hands it to the merge (tile_surface_bytes.hpp):
// read back bit for bit, and bytes that are not one refused with the key.
#include "ingest/tiles/tile_surface_bytes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "core/base/error.hpp"
#include "core/tiles/tiler.hpp"
#include "tests/support/test_terrain.hpp"

namespace tinsmith::ingest {
namespace {

using tiles::TileSurface;

std::uint64_t bitsOf(double v) {
  return std::bit_cast<std::uint64_t>(v);
}

void expectSameSurface(const TileSurface& a, const TileSurface& b) {
  EXPECT_EQ(a.id, b.id);
  for (const auto& [x, y] : {std::pair{a.bounds.x0, b.bounds.x0},
                             {a.bounds.y0, b.bounds.y0},
                             {a.bounds.x1, b.bounds.x1},
                             {a.bounds.y1, b.bounds.y1},
                             {a.error, b.error},
                             {a.tolerance, b.tolerance}})
    EXPECT_EQ(bitsOf(x), bitsOf(y));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) {
    EXPECT_EQ(bitsOf(a.vertices[i].x), bitsOf(b.vertices[i].x)) << i;
    EXPECT_EQ(bitsOf(a.vertices[i].y), bitsOf(b.vertices[i].y)) << i;
    EXPECT_EQ(bitsOf(a.vertices[i].z), bitsOf(b.vertices[i].z)) << i;
  }
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.heldEdges, b.heldEdges);
  EXPECT_EQ(a.riverEdges, b.riverEdges);
  EXPECT_EQ(a.flags, b.flags);
}

TEST(TileSurfaceBytes, ARealTileAndOddDoublesReadBackBitForBit) {
  TinData tin = test::rippledRiverTin();
  tin.crs = "EPSG:26912";
  tiles::TilerOptions options;
  options.tolerance = 0.05;
  options.maxTriangles = 1024;
  const tiles::Tiler tiler(tin, options);
  const TileSurface real = tiler.buildTile({2, 1, 2});
  ASSERT_FALSE(real.empty());
  ASSERT_NE(std::count(real.riverEdges.begin(), real.riverEdges.end(), 0), real.riverEdges.size())
      << "the tile holds part of the river";
  expectSameSurface(decodeTileSurface(encodeTileSurface(real), "real"), real);

  TileSurface odd;
  odd.id = {30, (1U << 30) - 1, 7};
  odd.bounds = {-0.0, std::numeric_limits<double>::denorm_min(), 1e300, -1e-300};
  odd.error = std::nextafter(0.25, 1.0);
  odd.vertices = {{-0.0, 0.1, std::numeric_limits<double>::max()}, {1, 2, 3}, {4, 5, -6}};
  odd.triangles = {{0, 1, 2}, {2, 1, 0}};
  odd.heldEdges = {7, 0};
  odd.riverEdges = {4, 0};
  odd.flags = {0x3f, 0, 0x10};
  expectSameSurface(decodeTileSurface(encodeTileSurface(odd), "odd"), odd);
  // An empty tile's too.
  TileSurface empty;
  empty.id = {2, 3, 3};
  expectSameSurface(decodeTileSurface(encodeTileSurface(empty), "empty"), empty);
  EXPECT_EQ(tileSurfaceKey({2, 3, 1}), "tinsmith/surfaces/2/3/1");
}

TEST(TileSurfaceBytes, BytesThatAreNotASurfaceAreRefusedNamingWhere) {
  TileSurface s;
  s.id = {2, 1, 1};
  s.vertices = {{0, 0, 1}, {1, 0, 2}, {0, 1, 3}};
  s.triangles = {{0, 1, 2}};
  s.heldEdges = {1};
  s.riverEdges = {0};
  s.flags = {0, 0, 0};
  const std::string good = encodeTileSurface(s);
  const auto refusal = [](const std::string& bytes) {
    try {
      (void)decodeTileSurface(bytes, "shard.3dtiles tinsmith/surfaces/2/1/1");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("read");
  };
  const auto expectRefused = [&](const std::string& bytes, const std::string& why) {
    const std::string what = refusal(bytes);
    EXPECT_NE(what.find("shard.3dtiles tinsmith/surfaces/2/1/1"), std::string::npos) << what;
    EXPECT_NE(what.find(why), std::string::npos) << what;
  };
  expectRefused("", "ends early");
  expectRefused("TSURFv99" + good.substr(8), "does not start with TSURFv01");
  for (const std::size_t cut : {good.size() - 1, good.size() / 2, std::size_t{20}})
    expectRefused(good.substr(0, cut), "ends early");
  expectRefused(good + "x", "more bytes follow it");
  // A corner past the vertices: the triangle's first corner follows the
  // header (8 + 12 + 48 + 16 bytes) and the vertices (3 · 24).
  std::string corner = good;
  corner[8 + 12 + 48 + 16 + 72] = 3;
  expectRefused(corner, "corner 3 is no vertex");
  // Counts larger than the bytes hold are refused before anything is made.
  std::string huge = good;
  huge[8 + 12 + 48 + 7] = '\x7f';
  expectRefused(huge, "ends early");
  std::string outside = good;
  outside[8 + 4] = 9;  // x = 9 at zoom 2
  expectRefused(outside, "outside its zoom");
  // Values no tile has: a NaN error, an infinite vertex, a fourth edge
  // bit, a river edge that is not held, a seventh flag bit.
  const auto with = [&](std::size_t at, const std::string& bytes) {
    std::string b = good;
    b.replace(at, bytes.size(), bytes);
    return b;
  };
  const std::string nan(8, '\xff');
  expectRefused(with(8 + 12 + 32, nan), "its error is");
  expectRefused(with(8 + 12 + 48 + 16 + 8, nan), "a vertex is not finite");
  const std::size_t bits = 8 + 12 + 48 + 16 + 72 + 12;  // held, river, then flags
  expectRefused(with(bits, "\x08"), "held edges are 8");
  expectRefused(with(bits + 1, "\x02"), "river edges are not among its held ones");
  expectRefused(with(bits + 2, "\x40"), "flags are 64");
  EXPECT_EQ(refusal(good), "read");
}

}  // namespace
}  // namespace tinsmith::ingest
