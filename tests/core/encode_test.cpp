// Earth frames and .glb tile content: frames against known values and each
// other; encodeGlb → decodeGlb round trips (Draco and plain) on terrain-like
// grids, the JSON a loader sees, determinism, size, and rejected input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/base/error.hpp"
#include "core/encode/frames.hpp"
#include "core/encode/glb.hpp"

namespace tinsmith::encode {
namespace {

constexpr double kPi = 3.14159265358979323846;

// --- frames ------------------------------------------------------------------

Point3 transformPoint(const Matrix4& m, const Point3& p) {
  return {m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12],
          m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
          m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]};
}

double separation(const Point3& a, const Point3& b) {
  return std::hypot(a.x - b.x, a.y - b.y, a.z - b.z);
}

TEST(EncodeFrames, EquatorOnThePrimeMeridianIsTheSemiMajorAxis) {
  const Point3 p = geodeticToEcef({0.0, 0.0, 0.0});
  EXPECT_NEAR(p.x, 6378137.0, 1e-9);
  EXPECT_NEAR(p.y, 0.0, 1e-9);
  EXPECT_NEAR(p.z, 0.0, 1e-9);
  const Point3 pole = geodeticToEcef({0.0, 90.0, 100.0});
  EXPECT_NEAR(pole.z, 6356752.314245179 + 100.0, 1e-6);
  const Point3 east = geodeticToEcef({90.0, 0.0, 0.0});
  EXPECT_NEAR(east.y, 6378137.0, 1e-9);
}

TEST(EncodeFrames, GeodeticEcefRoundTrip) {
  for (const Geodetic g :
       {Geodetic{0, 0, 0}, Geodetic{10.5, 46.25, 1512.3}, Geodetic{-122.4194, 37.7749, -30.0},
        Geodetic{179.9, -89.5, 8848.0}, Geodetic{-45.0, 60.0, 12000.0}}) {
    const Geodetic back = ecefToGeodetic(geodeticToEcef(g));
    EXPECT_NEAR(back.lon, g.lon, 1e-11);
    EXPECT_NEAR(back.lat, g.lat, 1e-11);
    EXPECT_NEAR(back.height, g.height, 1e-6);
  }
}

TEST(EncodeFrames, EnuMatrixTimesEnuCoordinatesIsEcef) {
  const Geodetic origin{10.5, 46.25, 1500.0};
  const EnuFrame frame(origin);
  EXPECT_LT(separation(frame.fromGeodetic(origin), {0, 0, 0}), 1e-9);
  const Point3 north = frame.fromGeodetic({origin.lon, origin.lat + 0.01, origin.height});
  EXPECT_GT(north.y, 1000.0);
  EXPECT_NEAR(north.x, 0.0, 1e-6);
  const Point3 east = frame.fromGeodetic({origin.lon + 0.01, origin.lat, origin.height});
  EXPECT_GT(east.x, 700.0);
  const Point3 up = frame.fromGeodetic({origin.lon, origin.lat, origin.height + 50.0});
  EXPECT_LT(separation(up, {0, 0, 50.0}), 1e-6);

  const Matrix4 m = frame.toEcefMatrix();
  EXPECT_EQ(m[15], 1.0);
  for (double dlon = -0.05; dlon <= 0.05; dlon += 0.025) {
    for (double dlat = -0.05; dlat <= 0.05; dlat += 0.025) {
      const Geodetic g{origin.lon + dlon, origin.lat + dlat, 800.0 + 2000.0 * dlat};
      EXPECT_LT(separation(transformPoint(m, frame.fromGeodetic(g)), geodeticToEcef(g)), 1e-6);
    }
  }
}

TEST(EncodeFrames, RootMatrixUndoesTheYUpTurn) {
  const Point3 centre = geodeticToEcef({10.5, 46.25, 1500.0});
  const Matrix4 m = zUpContentRootMatrix(centre);
  // T(x, y, z) = (x, −z, y): the turn 3D Tiles applies to glTF content.
  const auto yUpToZUp = [](const Point3& p) { return Point3{p.x, -p.z, p.y}; };
  for (const Point3 p : {Point3{0, 0, 0}, Point3{1, 2, 3}, Point3{-2500.5, 1800.25, -40.0}}) {
    const Point3 q = yUpToZUp(transformPoint(m, p));
    EXPECT_LT(separation(q, {p.x + centre.x, p.y + centre.y, p.z + centre.z}), 1e-9);
  }
}

TEST(EncodeFrames, PositionsOffTheGlobeThrowInputError) {
  try {
    geodeticToEcef({0.0, 91.0, 0.0});
    FAIL() << "latitude 91 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
  }
  EXPECT_THROW(EnuFrame({NAN, 0.0, 0.0}), Error);
  EXPECT_THROW(ecefToGeodetic({INFINITY, 0.0, 0.0}), Error);
}

// --- glb ---------------------------------------------------------------------

// An nx × ny grid of terrain 80 m apart, centred on the origin (a few km
// across, the size of tile content relative to its centre), with analytic
// normals and two counter-clockwise triangles per cell.
MeshBuffers terrainGrid(int nx, int ny, double spacing = 80.0) {
  MeshBuffers m;
  const double x0 = -0.5 * spacing * (nx - 1);
  const double y0 = -0.5 * spacing * (ny - 1);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = x0 + spacing * i;
      const double y = y0 + spacing * j;
      const double z = 300.0 * std::sin(x / 700.0) * std::cos(y / 900.0) + 0.02 * x;
      const double dzdx = 300.0 / 700.0 * std::cos(x / 700.0) * std::cos(y / 900.0) + 0.02;
      const double dzdy = -300.0 / 900.0 * std::sin(x / 700.0) * std::sin(y / 900.0);
      const double len = std::sqrt(dzdx * dzdx + dzdy * dzdy + 1.0);
      m.positions.push_back({float(x), float(y), float(z)});
      m.normals.push_back({float(-dzdx / len), float(-dzdy / len), float(1.0 / len)});
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const auto v = [&](int a, int b) { return std::uint32_t(b * nx + a); };
      m.indices.insert(m.indices.end(), {v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      m.indices.insert(m.indices.end(), {v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  }
  return m;
}

nlohmann::json jsonChunk(const std::string& glb) {
  std::uint32_t length = 0;
  std::memcpy(&length, glb.data() + 12, 4);
  return nlohmann::json::parse(glb.substr(20, length));
}

// A triangle as its vertex ids rotated to start at the smallest: orientation
// is kept, the starting corner is not.
using Triangle = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>;
Triangle canonical(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (b < a && b < c) return {b, c, a};
  if (c < a && c < b) return {c, a, b};
  return {a, b, c};
}

std::multiset<Triangle> triangles(const std::vector<std::uint32_t>& indices,
                                  const std::vector<std::uint32_t>& relabel) {
  std::multiset<Triangle> out;
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    out.insert(canonical(relabel[indices[t]], relabel[indices[t + 1]], relabel[indices[t + 2]]));
  }
  return out;
}

// Matches every decoded position to the original one within `tolerance` per
// coordinate (unique on a grid much coarser than the tolerance) and checks
// the matching is a bijection whose normals agree within `maxNormalDegrees`;
// then the relabelled triangles must be the original ones.
void expectSameMesh(const MeshBuffers& original, const MeshBuffers& decoded, double tolerance,
                    double maxNormalDegrees) {
  ASSERT_EQ(decoded.positions.size(), original.positions.size());
  ASSERT_EQ(decoded.normals.size(), original.normals.size());
  ASSERT_EQ(decoded.indices.size(), original.indices.size());
  std::vector<std::uint32_t> byX(original.positions.size());
  for (std::uint32_t i = 0; i < byX.size(); ++i) byX[i] = i;
  std::sort(byX.begin(), byX.end(),
            [&](auto a, auto b) { return original.positions[a][0] < original.positions[b][0]; });
  std::vector<std::uint32_t> toOriginal(decoded.positions.size());
  std::vector<bool> used(original.positions.size(), false);
  double worstPosition = 0.0;
  double worstNormal = 0.0;
  for (std::size_t d = 0; d < decoded.positions.size(); ++d) {
    const auto& p = decoded.positions[d];
    auto it = std::lower_bound(byX.begin(), byX.end(), p[0] - tolerance,
                               [&](auto i, float x) { return original.positions[i][0] < x; });
    std::uint32_t match = std::numeric_limits<std::uint32_t>::max();
    for (; it != byX.end() && original.positions[*it][0] <= p[0] + tolerance; ++it) {
      const auto& o = original.positions[*it];
      double err = 0.0;
      for (int c = 0; c < 3; ++c) err = std::max(err, std::abs(double(o[c]) - double(p[c])));
      if (err <= tolerance) {
        ASSERT_EQ(match, std::numeric_limits<std::uint32_t>::max()) << "two matches for " << d;
        match = *it;
        worstPosition = std::max(worstPosition, err);
      }
    }
    ASSERT_NE(match, std::numeric_limits<std::uint32_t>::max())
        << "decoded position " << d << " (" << p[0] << ", " << p[1] << ", " << p[2]
        << ") is not within " << tolerance << " m of an original";
    ASSERT_FALSE(used[match]) << "original " << match << " matched twice";
    used[match] = true;
    toOriginal[d] = match;
    const auto& n = decoded.normals[d];
    const auto& o = original.normals[match];
    const double dot = double(n[0]) * o[0] + double(n[1]) * o[1] + double(n[2]) * o[2];
    const double norm = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    worstNormal = std::max(worstNormal, std::acos(std::min(1.0, dot / norm)) * 180.0 / kPi);
  }
  EXPECT_LE(worstNormal, maxNormalDegrees);
  std::vector<std::uint32_t> identity(original.positions.size());
  for (std::uint32_t i = 0; i < identity.size(); ++i) identity[i] = i;
  EXPECT_EQ(triangles(decoded.indices, toOriginal), triangles(original.indices, identity));
}

// Positions are float: besides Draco's quantization error a coordinate may
// round by a few float ulps of the largest coordinate.
double floatSlack(const MeshBuffers& m) {
  float largest = 0.0f;
  for (const auto& p : m.positions) {
    for (float v : p) largest = std::max(largest, std::abs(v));
  }
  return 4.0 * std::numeric_limits<float>::epsilon() * largest;
}

TEST(EncodeGlb, DracoRoundTripKeepsTrianglesWithinTheReportedBound) {
  const MeshBuffers grid = terrainGrid(50, 50);
  for (const double maxError : {0.01, 0.001, 0.5}) {
    SCOPED_TRACE(maxError);
    GlbOptions options;
    options.maxPositionError = maxError;
    const Matrix4 root = zUpContentRootMatrix(geodeticToEcef({10.5, 46.25, 1500.0}));
    const GlbResult r = encodeGlb(grid, root, options);
    EXPECT_LE(r.positionErrorBound, maxError);
    EXPECT_GE(r.positionBits, 1);
    EXPECT_LE(r.positionBits, 30);
    // The fewest bits: one fewer would exceed the error asked for. The bound
    // is a distance: √3 × the half step each coordinate rounds to.
    const double range = 80.0 * 49;
    EXPECT_NEAR(r.positionErrorBound, std::sqrt(3.0) * range / ((1u << r.positionBits) - 1) / 2,
                1e-12);
    EXPECT_GT(std::sqrt(3.0) * range / ((1u << (r.positionBits - 1)) - 1) / 2, maxError);

    const DecodedGlb d = decodeGlb(r.bytes, "grid.glb");
    EXPECT_TRUE(d.draco);
    EXPECT_EQ(d.rootMatrix, root);
    EXPECT_EQ(d.assetExtras, "");
    expectSameMesh(grid, d.mesh, r.positionErrorBound + floatSlack(grid), 0.5);
  }
}

TEST(EncodeGlb, DecodedPositionsAreWhatDracoDecodes) {
  // Each decoded position, bit for bit, is decodedPositions' for its vertex
  // (Draco may reorder the vertices: matched by the triangles' corners).
  MeshBuffers grid = terrainGrid(40, 30);
  for (auto& p : grid.positions) p[2] += 0.37f * p[0] - 1e-3f * p[1];  // a tilt, odd values
  for (const double maxError : {0.01, 0.0005, 0.2}) {
    SCOPED_TRACE(maxError);
    GlbOptions options;
    options.maxPositionError = maxError;
    const auto expected = decodedPositions(grid, options);
    ASSERT_EQ(expected.size(), grid.positions.size());
    const DecodedGlb d = decodeGlb(encodeGlb(grid, zUpContentRootMatrix({}), options).bytes, "g");
    std::multiset<std::array<float, 3>> want(expected.begin(), expected.end());
    std::size_t found = 0;
    for (const auto& p : d.mesh.positions) found += want.count(p) > 0 ? 1 : 0;
    EXPECT_EQ(found, d.mesh.positions.size());
    double moved = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      moved =
          std::max(moved, static_cast<double>(std::hypot(expected[i][0] - grid.positions[i][0],
                                                         expected[i][1] - grid.positions[i][1],
                                                         expected[i][2] - grid.positions[i][2])));
    }
    EXPECT_GT(moved, 0.0);
    EXPECT_LE(moved, maxError + floatSlack(grid));
  }
  GlbOptions plain;
  plain.compression = Compression::None;
  EXPECT_EQ(decodedPositions(grid, plain), grid.positions);
}

TEST(EncodeGlb, PlainRoundTripIsExact) {
  const MeshBuffers grid = terrainGrid(50, 50);
  GlbOptions options;
  options.compression = Compression::None;
  const GlbResult r = encodeGlb(grid, zUpContentRootMatrix({100.0, -200.0, 300.0}), options);
  EXPECT_EQ(r.positionBits, 0);
  EXPECT_EQ(r.positionErrorBound, 0.0);
  const DecodedGlb d = decodeGlb(r.bytes, "grid.glb");
  EXPECT_FALSE(d.draco);
  EXPECT_EQ(d.mesh.positions, grid.positions);
  EXPECT_EQ(d.mesh.normals, grid.normals);
  EXPECT_EQ(d.mesh.indices, grid.indices);
  EXPECT_EQ(d.rootMatrix, zUpContentRootMatrix({100.0, -200.0, 300.0}));
}

TEST(EncodeGlb, JsonIsWhatALoaderNeeds) {
  const MeshBuffers grid = terrainGrid(10, 12);
  const Matrix4 identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (const Compression compression : {Compression::Draco, Compression::None}) {
    GlbOptions options;
    options.compression = compression;
    const std::string bytes = encodeGlb(grid, identity, options).bytes;
    ASSERT_EQ(bytes.size() % 4, 0u);
    EXPECT_EQ(bytes.substr(0, 4), "glTF");
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 8, 4);
    EXPECT_EQ(length, bytes.size());
    const nlohmann::json j = jsonChunk(bytes);
    EXPECT_EQ(j["asset"]["version"], "2.0");
    EXPECT_EQ(j["asset"]["generator"].get<std::string>().rfind("tinsmith", 0), 0u);
    EXPECT_FALSE(j["asset"].contains("extras"));
    EXPECT_EQ(j["scene"], 0);
    ASSERT_EQ(j["nodes"].size(), 1u);
    EXPECT_FALSE(j["nodes"][0].contains("matrix")) << "identity is omitted";
    const auto& primitive = j["meshes"][0]["primitives"][0];
    EXPECT_EQ(primitive["mode"], 4);
    // A matte material, not glTF's default metal.
    ASSERT_TRUE(primitive.contains("material"));
    const auto& pbr = j["materials"][primitive["material"].get<int>()]["pbrMetallicRoughness"];
    EXPECT_EQ(pbr["metallicFactor"], 0.0);
    EXPECT_EQ(pbr["roughnessFactor"], 1.0);
    const auto& position = j["accessors"][primitive["attributes"]["POSITION"].get<int>()];
    EXPECT_EQ(position["componentType"], 5126);
    EXPECT_EQ(position["type"], "VEC3");
    EXPECT_EQ(position["count"], 120);
    EXPECT_EQ(position["min"][0], -360.0);
    EXPECT_EQ(position["max"][1], 440.0);
    const auto& indices = j["accessors"][primitive["indices"].get<int>()];
    EXPECT_EQ(indices["componentType"], 5123);
    EXPECT_EQ(indices["count"], grid.indices.size());
    EXPECT_EQ(j["buffers"].size(), 1u);
    if (compression == Compression::Draco) {
      EXPECT_EQ(j["extensionsUsed"], nlohmann::json::array({"KHR_draco_mesh_compression"}));
      EXPECT_EQ(j["extensionsRequired"], nlohmann::json::array({"KHR_draco_mesh_compression"}));
      const auto& ext = primitive["extensions"]["KHR_draco_mesh_compression"];
      EXPECT_EQ(ext["bufferView"], 0);
      EXPECT_TRUE(ext["attributes"].contains("POSITION"));
      EXPECT_TRUE(ext["attributes"].contains("NORMAL"));
      for (const auto& a : j["accessors"]) EXPECT_FALSE(a.contains("bufferView"));
    } else {
      EXPECT_FALSE(j.contains("extensionsRequired"));
      const auto& views = j["bufferViews"];
      ASSERT_EQ(views.size(), 3u);
      EXPECT_EQ(views[position["bufferView"].get<int>()]["target"], 34962);
      const auto& indexView = views[indices["bufferView"].get<int>()];
      EXPECT_EQ(indexView["target"], 34963);
      EXPECT_EQ(indexView.value("byteOffset", 0) % 4, 0);
    }
  }
}

TEST(EncodeGlb, IndicesAreUnsignedIntFrom65536Positions) {
  const Matrix4 identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (const Compression compression : {Compression::Draco, Compression::None}) {
    GlbOptions options;
    options.compression = compression;
    const auto indexType = [&](const MeshBuffers& m) {
      const nlohmann::json j = jsonChunk(encodeGlb(m, identity, options).bytes);
      return j["accessors"][j["meshes"][0]["primitives"][0]["indices"].get<int>()]["componentType"]
          .get<int>();
    };
    EXPECT_EQ(indexType(terrainGrid(255, 257, 10.0)), 5123);  // 65 535 positions
    const MeshBuffers big = terrainGrid(256, 256, 10.0);      // 65 536
    EXPECT_EQ(indexType(big), 5125);
    const DecodedGlb d = decodeGlb(encodeGlb(big, identity, options).bytes, "big.glb");
    EXPECT_EQ(d.mesh.positions.size(), 65536u);
    EXPECT_EQ(d.mesh.indices.size(), big.indices.size());
    EXPECT_EQ(*std::max_element(d.mesh.indices.begin(), d.mesh.indices.end()), 65535u);
  }
}

TEST(EncodeGlb, AccessorCountsAreWhatDracoDecodes) {
  // An unreferenced position: Draco's edgebreaker drops it, so the accessor
  // count must come from what was encoded, not from the input.
  MeshBuffers m = terrainGrid(8, 8);
  m.positions.push_back({5000.0f, 5000.0f, 0.0f});
  m.normals.push_back({0.0f, 0.0f, 1.0f});
  const std::string bytes = encodeGlb(m, zUpContentRootMatrix({}), GlbOptions{}).bytes;
  const DecodedGlb d = decodeGlb(bytes, "unreferenced.glb");
  const nlohmann::json j = jsonChunk(bytes);
  const auto& primitive = j["meshes"][0]["primitives"][0];
  EXPECT_EQ(j["accessors"][primitive["attributes"]["POSITION"].get<int>()]["count"],
            d.mesh.positions.size());
  EXPECT_EQ(j["accessors"][primitive["attributes"]["NORMAL"].get<int>()]["count"],
            d.mesh.normals.size());
  EXPECT_EQ(j["accessors"][primitive["indices"].get<int>()]["count"], d.mesh.indices.size());
  EXPECT_EQ(d.mesh.indices.size(), m.indices.size());
}

TEST(EncodeGlb, SameMeshAndOptionsGiveTheSameBytes) {
  const MeshBuffers grid = terrainGrid(40, 30);
  GlbOptions options;
  options.assetExtras = R"({"tile":"3/2/5","geometricError":12.5})";
  for (const Compression compression : {Compression::Draco, Compression::None}) {
    options.compression = compression;
    const Matrix4 root = zUpContentRootMatrix({4.2e6, 8.1e5, 4.7e6});
    EXPECT_EQ(encodeGlb(grid, root, options).bytes, encodeGlb(grid, root, options).bytes);
  }
}

TEST(EncodeGlb, DracoIsUnderAQuarterOfPlain) {
  const MeshBuffers grid = terrainGrid(100, 100);
  const Matrix4 root = zUpContentRootMatrix(geodeticToEcef({10.5, 46.25, 1500.0}));
  GlbOptions options;
  const GlbResult draco = encodeGlb(grid, root, options);
  options.compression = Compression::None;
  const GlbResult plain = encodeGlb(grid, root, options);
  const double ratio = double(draco.bytes.size()) / double(plain.bytes.size());
  std::printf(
      "100x100 grid: Draco %zu bytes (%d position bits, bound %.4g m), plain %zu bytes, "
      "ratio %.3f\n",
      draco.bytes.size(), draco.positionBits, draco.positionErrorBound, plain.bytes.size(), ratio);
  RecordProperty("draco_to_plain_ratio", std::to_string(ratio));
  EXPECT_LT(ratio, 0.25);
}

TEST(EncodeGlb, AssetExtrasRoundTripAsCompactJson) {
  GlbOptions options;
  options.assetExtras =
      R"({ "tinsmith": {"tile": "3/2/5", "maxError": 0.25, "empty": [], "none": {},
           "big": 5000000000, "negative": -7} })";
  for (const Compression compression : {Compression::Draco, Compression::None}) {
    options.compression = compression;
    const DecodedGlb d = decodeGlb(encodeGlb(terrainGrid(4, 4), {}, options).bytes, "x.glb");
    EXPECT_EQ(d.assetExtras, R"({"tinsmith":{"tile":"3/2/5","maxError":0.25,"empty":[],"none":{},)"
                             R"("big":5000000000,"negative":-7}})");
  }
}

void expectInputError(const MeshBuffers& m, const std::string& word) {
  for (const Compression compression : {Compression::Draco, Compression::None}) {
    GlbOptions options;
    options.compression = compression;
    try {
      encodeGlb(m, {}, options);
      ADD_FAILURE() << "accepted a mesh with " << word;
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  }
}

TEST(EncodeGlb, BadMeshesThrowInputError) {
  expectInputError(MeshBuffers{}, "no positions");
  MeshBuffers noTriangles = terrainGrid(3, 3);
  noTriangles.indices.clear();
  expectInputError(noTriangles, "no triangles");
  MeshBuffers outOfRange = terrainGrid(3, 3);
  outOfRange.indices[4] = 9;
  expectInputError(outOfRange, "triangle 1 uses position 9");
  MeshBuffers ragged = terrainGrid(3, 3);
  ragged.indices.pop_back();
  expectInputError(ragged, "not a multiple of 3");
  MeshBuffers fewNormals = terrainGrid(3, 3);
  fewNormals.normals.pop_back();
  expectInputError(fewNormals, "8 normals for 9 positions");
  MeshBuffers nan = terrainGrid(3, 3);
  nan.positions[5][2] = NAN;
  expectInputError(nan, "not finite");
}

TEST(EncodeGlb, BadOptionsThrow) {
  const MeshBuffers grid = terrainGrid(3, 3);
  GlbOptions options;
  options.maxPositionError = 0.0;
  EXPECT_THROW(encodeGlb(grid, {}, options), Error);
  options = {};
  options.normalBits = 1;
  EXPECT_THROW(encodeGlb(grid, {}, options), Error);
  options = {};
  options.assetExtras = "[1, 2]";
  try {
    encodeGlb(grid, {}, options);
    ADD_FAILURE() << "accepted extras that are not an object";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
  }
  options.assetExtras = "{not json";
  EXPECT_THROW(encodeGlb(grid, {}, options), Error);
}

TEST(EncodeGlb, DecodingBadBytesThrowsInputErrorNamingTheFile) {
  const std::string good = encodeGlb(terrainGrid(5, 5), {}, GlbOptions{}).bytes;
  std::string badMagic = good;
  badMagic[0] = 'x';
  std::string badDraco = good;
  badDraco[badDraco.size() - 20] ^= 0x5a;  // inside the Draco bytes: decoding fails or
  badDraco[badDraco.size() - 40] ^= 0x5a;  // the mesh it gives fails the checks
  for (const std::string& bytes :
       {std::string("hello"), badMagic, good.substr(0, good.size() / 2), good.substr(0, 30)}) {
    try {
      decodeGlb(bytes, "tiles/3/2/5.glb");
      ADD_FAILURE() << "decoded " << bytes.size() << " bad bytes";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("tiles/3/2/5.glb"), std::string::npos) << e.what();
    }
  }
  try {
    decodeGlb(badDraco, "bad.glb");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
  }
}

// Every truncation (with the header's length patched to match, so parsing
// goes past the header) and every single-byte change of a small .glb either
// decodes to a consistent mesh or throws inputError.
TEST(EncodeGlb, TruncatedOrCorruptedGlbDecodesOrThrowsInputError) {
  for (const Compression compression : {Compression::Draco, Compression::None}) {
    GlbOptions options;
    options.compression = compression;
    const std::string good = encodeGlb(terrainGrid(4, 3), {}, options).bytes;
    const auto check = [](const std::string& bytes) {
      try {
        const DecodedGlb d = decodeGlb(bytes, "fuzzed.glb");
        for (std::uint32_t i : d.mesh.indices) ASSERT_LT(i, d.mesh.positions.size());
      } catch (const Error& e) {
        ASSERT_EQ(e.kind(), ErrorKind::Input) << e.what();
      }
    };
    for (std::size_t k = 0; k < good.size(); ++k) {
      std::string cut = good.substr(0, k);
      if (k >= 12) {
        const auto length = static_cast<std::uint32_t>(k);
        std::memcpy(cut.data() + 8, &length, 4);
      }
      check(cut);
    }
    for (std::size_t k = 0; k < good.size(); ++k) {
      for (const unsigned char flip : {0x01, 0x80, 0xff}) {
        std::string bad = good;
        bad[k] = static_cast<char>(bad[k] ^ flip);
        check(bad);
      }
    }
  }
}

}  // namespace
}  // namespace tinsmith::encode
