// quantized-mesh-1.0 tiles (core/encode/quantized_mesh.hpp), read back by the
// tests' own reader written from the format's text
// (tests/support/quantized_mesh_decoder.hpp).
#include "core/encode/quantized_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/base/error.hpp"
#include "core/encode/frames.hpp"
#include "tests/support/quantized_mesh_decoder.hpp"

namespace tinsmith::encode {
namespace {

/// A k × k grid over the tile, two triangles a cell, counter-clockwise,
/// heights from a formula; its edge lists; vertices in row order (not the
/// order the triangles first use them).
QuantizedMeshTile gridTile(int k) {
  QuantizedMeshTile t;
  t.centre = {1.0e6, 2.0e6, 3.0e6};
  t.minHeight = 1000.5f;
  t.maxHeight = 1234.25f;
  t.sphereCentre = {1.0e6 + 1, 2.0e6 - 2, 3.0e6 + 3};
  t.sphereRadius = 4567.875;
  t.horizonOcclusion = {0.1, 0.2, 0.9};
  auto q = [&](int i) { return static_cast<std::uint16_t>(std::lround(32767.0 * i / (k - 1))); };
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      t.u.push_back(q(i));
      t.v.push_back(q(j));
      t.height.push_back(static_cast<std::uint16_t>((i * 7919 + j * 104729) % 32768));
    }
  auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * k + i); };
  for (int j = 0; j + 1 < k; ++j)
    for (int i = 0; i + 1 < k; ++i) {
      t.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int s = 0; s < k; ++s) {
    t.edges[0].push_back(at(0, s));
    t.edges[1].push_back(at(s, 0));
    t.edges[2].push_back(at(k - 1, s));
    t.edges[3].push_back(at(s, k - 1));
  }
  return t;
}

/// Checks that `decoded` is `tile` (after inFirstUseOrder) field by field.
void expectSame(const QuantizedMeshTile& tile, const test::DecodedQuantizedMesh& d) {
  ASSERT_TRUE(d.ok) << "bytes missing or left over";
  EXPECT_EQ(d.centre, (std::array{tile.centre.x, tile.centre.y, tile.centre.z}));
  EXPECT_EQ(d.minHeight, tile.minHeight);
  EXPECT_EQ(d.maxHeight, tile.maxHeight);
  EXPECT_EQ(d.sphereCentre,
            (std::array{tile.sphereCentre.x, tile.sphereCentre.y, tile.sphereCentre.z}));
  EXPECT_EQ(d.sphereRadius, tile.sphereRadius);
  EXPECT_EQ(d.horizonOcclusion, (std::array{tile.horizonOcclusion.x, tile.horizonOcclusion.y,
                                            tile.horizonOcclusion.z}));
  EXPECT_EQ(d.u, tile.u);
  EXPECT_EQ(d.v, tile.v);
  EXPECT_EQ(d.height, tile.height);
  std::vector<std::uint32_t> indices;
  for (const auto& t : tile.triangles) indices.insert(indices.end(), t.begin(), t.end());
  EXPECT_EQ(d.indices, indices);
  for (int e = 0; e < 4; ++e) EXPECT_EQ(d.edges[e], tile.edges[e]) << "edge " << e;
}

TEST(QuantizedMesh, ATileReadsBackAsWrittenWithItsExtensions) {
  QuantizedMeshTile tile = inFirstUseOrder(gridTile(17));
  for (std::size_t i = 0; i < tile.u.size(); ++i) tile.octNormals.push_back(octEncode({0, 0, 1}));
  tile.waterMask = std::vector<std::uint8_t>(256 * 256, 0);
  (*tile.waterMask)[5] = 255;
  tile.metadata = R"({"available":[[{"startX":0,"startY":0,"endX":1,"endY":1}]]})";
  const std::string bytes = encodeQuantizedMesh(tile);
  const auto d = test::decodeQuantizedMesh(bytes);
  expectSame(tile, d);
  EXPECT_FALSE(d.wideIndices);
  ASSERT_EQ(d.extensions.size(), 3u);
  EXPECT_EQ(d.extensions.at(1).size(), 2 * tile.u.size());
  EXPECT_EQ(d.extensions.at(2).size(), 65536u);
  EXPECT_EQ(static_cast<unsigned char>(d.extensions.at(2)[5]), 255);
  const std::string& meta = d.extensions.at(4);
  std::uint32_t length = 0;
  std::memcpy(&length, meta.data(), 4);
  EXPECT_EQ(length, tile.metadata->size());
  EXPECT_EQ(meta.substr(4), *tile.metadata);
}

TEST(QuantizedMesh, PastSixtyFourKiVerticesIndicesAreThirtyTwoBitsAndAligned) {
  // 257 × 257 = 66 049 vertices. After the 88-byte header, the count and 3 ×
  // 66 049 two-byte values the offset is 396 386: two bytes of padding.
  const QuantizedMeshTile tile = inFirstUseOrder(gridTile(257));
  const std::string bytes = encodeQuantizedMesh(tile);
  const auto d = test::decodeQuantizedMesh(bytes);
  EXPECT_TRUE(d.wideIndices);
  expectSame(tile, d);
  std::uint32_t triangles = 0;
  std::memcpy(&triangles, bytes.data() + 396388, 4);
  EXPECT_EQ(triangles, tile.triangles.size()) << "the triangle count after the padding";
}

TEST(QuantizedMesh, ValuesAreZigZagDeltasAndIndicesAHighWaterMark) {
  QuantizedMeshTile tile;
  tile.u = {0, 32767, 0, 100};
  tile.v = {0, 0, 32767, 100};
  tile.height = {5, 3, 32767, 0};
  tile.triangles = {{0, 1, 2}, {1, 3, 2}};
  const std::string bytes = encodeQuantizedMesh(tile);
  auto u16 = [&](std::size_t offset) {
    std::uint16_t x = 0;
    std::memcpy(&x, bytes.data() + offset, 2);
    return x;
  };
  // u: +0, +32767, −32767, +100 → 0, 65534, 65533, 200.
  EXPECT_EQ(u16(92), 0);
  EXPECT_EQ(u16(94), 65534);
  EXPECT_EQ(u16(96), 65533);
  EXPECT_EQ(u16(98), 200);
  // height: +5, −2 → 10, 3.
  EXPECT_EQ(u16(92 + 16), 10);
  EXPECT_EQ(u16(92 + 18), 3);
  // Triangles from byte 116: count, then 0 0 0 (three new vertices), then
  // 1 → highest 3 − 1 = 2, 3 → 0 (new), 2 → 4 − 2 = 2.
  const std::size_t first = 92 + 24 + 4;
  EXPECT_EQ(u16(first), 0);
  EXPECT_EQ(u16(first + 2), 0);
  EXPECT_EQ(u16(first + 4), 0);
  EXPECT_EQ(u16(first + 6), 2);
  EXPECT_EQ(u16(first + 8), 0);
  EXPECT_EQ(u16(first + 10), 2);
  expectSame(tile, test::decodeQuantizedMesh(bytes));
}

TEST(QuantizedMesh, BadTilesAreRefusedNotWritten) {
  QuantizedMeshTile tile = gridTile(3);
  EXPECT_THROW(encodeQuantizedMesh(tile), Error) << "row order is not first-use order here";
  tile = inFirstUseOrder(tile);
  EXPECT_NO_THROW(encodeQuantizedMesh(tile));
  auto bad = tile;
  bad.u[0] = 40000;
  EXPECT_THROW(encodeQuantizedMesh(bad), Error);
  bad = tile;
  bad.triangles[0][1] = 99;
  EXPECT_THROW(encodeQuantizedMesh(bad), Error);
  bad = tile;
  bad.edges[2].push_back(99);
  EXPECT_THROW(encodeQuantizedMesh(bad), Error);
  bad = tile;
  bad.waterMask = std::vector<std::uint8_t>(3, 0);
  EXPECT_THROW(encodeQuantizedMesh(bad), Error);
  bad = tile;
  bad.v.pop_back();
  EXPECT_THROW(encodeQuantizedMesh(bad), Error);
}

TEST(QuantizedMesh, FirstUseOrderKeepsTheMeshAndItsEdges) {
  const QuantizedMeshTile grid = gridTile(9);
  const QuantizedMeshTile ordered = inFirstUseOrder(grid);
  ASSERT_EQ(ordered.u.size(), grid.u.size());
  auto position = [](const QuantizedMeshTile& t, std::uint32_t i) {
    return std::array{t.u[i], t.v[i], t.height[i]};
  };
  for (std::size_t k = 0; k < grid.triangles.size(); ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(position(ordered, ordered.triangles[k][c]), position(grid, grid.triangles[k][c]));
  for (int e = 0; e < 4; ++e)
    for (std::size_t k = 0; k < grid.edges[e].size(); ++k)
      EXPECT_EQ(position(ordered, ordered.edges[e][k]), position(grid, grid.edges[e][k]));
}

TEST(QuantizedMesh, OctNormalsDecodeWithinAboutADegree) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    Point3 n{g(rng), g(rng), g(rng)};
    const double l = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
    n = {n.x / l, n.y / l, n.z / l};
    const Point3 back = octDecode(octEncode(n));
    worst = std::max(worst,
                     std::acos(std::clamp(n.x * back.x + n.y * back.y + n.z * back.z, -1.0, 1.0)));
  }
  EXPECT_LT(worst * 180 / std::numbers::pi, 1.5);
  // The poles of the octahedron are exact.
  const Point3 up = octDecode(octEncode({0, 0, 1}));
  EXPECT_NEAR(up.z, 1.0, 1e-4);
  const Point3 down = octDecode(octEncode({0, 0, -1}));
  EXPECT_NEAR(down.z, -1.0, 1e-4);
}

TEST(QuantizedMesh, EveryPointIsOverTheHorizonOfTheOcclusionPointAndNoNearerOneWouldDo) {
  // A 1° tile at 45° N with heights 0 to 4 000 m.
  std::vector<Point3> points;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      points.push_back(geodeticToEcef({10 + 0.1 * i, 45 + 0.1 * j, 400.0 * ((i + j) % 11)}));
  const Point3 centre = geodeticToEcef({10.5, 45.5, 0});
  const Point3 p = horizonOcclusionPoint(points, centre);
  constexpr double a = 6378137.0, b = 6356752.3142451793;
  // From P, in the ellipsoid-scaled frame (the ellipsoid a unit sphere), a
  // point is in sight when the segment to it stays out of the sphere.
  auto minDistanceToOrigin = [](const Point3& from, const Point3& to) {
    const Point3 d{to.x - from.x, to.y - from.y, to.z - from.z};
    const double t = std::clamp(
        -(from.x * d.x + from.y * d.y + from.z * d.z) / (d.x * d.x + d.y * d.y + d.z * d.z), 0.0,
        1.0);
    return std::hypot(from.x + t * d.x, from.y + t * d.y, from.z + t * d.z);
  };
  double nearest = HUGE_VAL;
  for (const Point3& q : points) {
    const Point3 s{q.x / a, q.y / a, q.z / b};
    nearest = std::min(nearest, minDistanceToOrigin(p, s));
  }
  EXPECT_GE(nearest, 1.0 - 1e-9);
  // 0.1 % nearer the Earth, some point is below its horizon.
  const Point3 closer{p.x * 0.999, p.y * 0.999, p.z * 0.999};
  double closest = HUGE_VAL;
  for (const Point3& q : points)
    closest = std::min(closest, minDistanceToOrigin(closer, {q.x / a, q.y / a, q.z / b}));
  EXPECT_LT(closest, 1.0);
}

TEST(QuantizedMesh, TheHeadersSphereHoldsEveryPosition) {
  std::vector<Point3> points;
  for (int i = 0; i <= 8; ++i)
    for (int j = 0; j <= 8; ++j)
      points.push_back(
          geodeticToEcef({-111.8 + 0.01 * i, 40.78 + 0.01 * j, 1500.0 + 37.0 * i * j}));
  QuantizedMeshTile tile;
  setBoundingVolumes(tile, points);
  for (const Point3& p : points)
    EXPECT_LE(
        std::hypot(p.x - tile.sphereCentre.x, p.y - tile.sphereCentre.y, p.z - tile.sphereCentre.z),
        tile.sphereRadius * (1 + 1e-12));
  // 0.08° × 0.08° (6.7 km × 8.9 km, 2.4 km of relief): the sphere is of the
  // tile's size (half its diagonal is 5.6 km), not the Earth's.
  EXPECT_LT(tile.sphereRadius, 8000.0);
  EXPECT_GT(tile.sphereRadius, 5500.0);
  EXPECT_EQ(tile.centre, tile.sphereCentre);
  EXPECT_THROW(setBoundingVolumes(tile, {}), Error);
}

TEST(QuantizedMesh, ATerrainTileDecodesWhereItsDecodedPositionsSayAndNoFarther) {
  // A 0.02° tile near Red Butte, a 21 × 21 grid over it (84 m × 111 m
  // cells), 1 680–1 720 m: slopes up to about 4°.
  GeodeticMesh mesh;
  mesh.west = -111.84;
  mesh.south = 40.78;
  mesh.east = -111.82;
  mesh.north = 40.80;
  constexpr int k = 21;
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i)
      mesh.vertices.push_back({mesh.west + 0.001 * i, mesh.south + 0.001 * j,
                               1700.0 + 20.0 * std::sin(0.3 * i) * std::cos(0.2 * j)});
  for (std::uint32_t j = 0; j + 1 < k; ++j)
    for (std::uint32_t i = 0; i + 1 < k; ++i) {
      const std::uint32_t a = j * k + i;
      mesh.triangles.push_back({a, a + 1, a + k + 1});
      mesh.triangles.push_back({a, a + k + 1, a + k});
    }
  const QuantizedTerrain q = quantizeTerrain(mesh);
  const auto d = test::decodeQuantizedMesh(encodeQuantizedMesh(q.tile));
  ASSERT_TRUE(d.ok);
  // What a client computes from the bytes alone is `decoded`.
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const std::uint32_t t = q.index[i];
    const double lon = mesh.west + (mesh.east - mesh.west) * d.u[t] / 32767.0;
    const double lat = mesh.south + (mesh.north - mesh.south) * d.v[t] / 32767.0;
    const double h =
        d.minHeight + (static_cast<double>(d.maxHeight) - d.minHeight) * d.height[t] / 32767.0;
    const Point3 client = geodeticToEcef({lon, lat, h});
    EXPECT_NEAR(client.x, q.decoded[i].x, 1e-6);
    EXPECT_NEAR(client.y, q.decoded[i].y, 1e-6);
    EXPECT_NEAR(client.z, q.decoded[i].z, 1e-6);
    const Point3 exact = geodeticToEcef(mesh.vertices[i]);
    EXPECT_LE(std::hypot(client.x - exact.x, client.y - exact.y, client.z - exact.z),
              q.maxMove + 1e-9);
  }
  // Half a step of 1/32767 of 1.7 km across, 2.2 km north and 40 m up.
  EXPECT_GT(q.maxMove, 0.0);
  EXPECT_LT(q.maxMove, 0.5 * std::hypot(1700.0, 2230.0, 40.0) / 32767 * 1.01);
  // The sides' vertices, and no others, in the edge lists.
  for (int e = 0; e < 4; ++e) EXPECT_EQ(d.edges[e].size(), static_cast<std::size_t>(k)) << e;
  for (int s = 0; s < k; ++s) {
    EXPECT_EQ(d.u[q.index[s * k]], 0);
    EXPECT_EQ(d.v[q.index[s]], 0);
  }
  // Normals: outward and in ECEF — each decodes within 6° of the
  // ellipsoid's up (8-bit oct encoding adds up to about a degree).
  ASSERT_EQ(d.extensions.count(1), 1u);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const std::string& oct = d.extensions.at(1);
    const std::uint32_t t = q.index[i];
    const Point3 n = octDecode(
        {static_cast<std::uint8_t>(oct[2 * t]), static_cast<std::uint8_t>(oct[2 * t + 1])});
    const double lon = mesh.vertices[i].lon * std::numbers::pi / 180,
                 lat = mesh.vertices[i].lat * std::numbers::pi / 180;
    const Point3 up{std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
    EXPECT_GT(n.x * up.x + n.y * up.y + n.z * up.z, std::cos(6 * std::numbers::pi / 180)) << i;
  }
}

}  // namespace
}  // namespace tinsmith::encode
