// Cesium terrain (tinsmith tile --scheme quantized-mesh) judged as a client
// sees it: every .terrain of a store decoded by the tests' own reader
// (tests/support/quantized_mesh_decoder.hpp), its u, v, heights turned into
// longitude, latitude and height as CesiumJS does, and held to
//   - the store: layer.json's "available" is exactly the tiles stored, every
//     tile's parent is there, both level-0 tiles are, the metadata of a
//     level-0 tile lists the tiles below it;
//   - the format: the edge lists are exactly the vertices on each side, the
//     header's sphere holds every vertex, the record in the metadata names
//     the tile;
//   - the surface: at every vertex over the TIN and every straight ECEF chord
//     middle between two such vertices, the 3-D distance to the TIN is
//     within the tile's declared error, and that within CesiumJS's error for
//     the level (77 067 m / 2^level) unless the summary names the tile as
//     missed;
//   - the sides: two tiles of one level that share a side have the same
//     vertices along it (the same quantized positions along the side, heights
//     within both tiles' quantization).
// On Red Butte (contours, streams, a reservoir as a lake), a mesa with 500 m
// walls over one metre, a 40 km flat plain, a pit, a TIN across the
// antimeridian; a TIN around a pole is refused and leaves no store.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>

#include "core/encode/frames.hpp"
#include "core/encode/quantized_mesh.hpp"
#include "core/tiles/geographic_grid.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/tile_content.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/quantized_mesh_decoder.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/tin_distance.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;
using tiles::TileId;

struct TerrainTile {
  TileId id;  ///< of the grid (TMS)
  tiles::GeoRect bounds;
  test::DecodedQuantizedMesh mesh;
  tiles::TileRecord record;
  std::size_t bytes = 0;

  [[nodiscard]] encode::Geodetic vertex(std::size_t i) const {
    const double s = 1.0 / encode::kQuantizedMax;
    return {bounds.west + (bounds.east - bounds.west) * (mesh.u[i] * s),
            bounds.south + (bounds.north - bounds.south) * (mesh.v[i] * s),
            mesh.minHeight + (double(mesh.maxHeight) - mesh.minHeight) * (mesh.height[i] * s)};
  }
  /// Half a step of the tile's height quantization (m).
  [[nodiscard]] double heightHalfStep() const {
    return 0.5 * (double(mesh.maxHeight) - mesh.minHeight) / encode::kQuantizedMax;
  }
};

/// The metadata extension's JSON (after its 32-bit length).
nlohmann::json metadataOf(const test::DecodedQuantizedMesh& mesh) {
  const std::string& bytes = mesh.extensions.at(encode::kMetadata);
  std::uint32_t length = 0;
  EXPECT_GE(bytes.size(), 4u);
  std::memcpy(&length, bytes.data(), 4);
  EXPECT_EQ(length + 4u, bytes.size());
  return nlohmann::json::parse(bytes.substr(4));
}

struct TerrainStore {
  std::vector<TerrainTile> tiles;
  nlohmann::json layer;
};

TerrainStore readTerrainStore(const fs::path& store) {
  TerrainStore out;
  out.layer = nlohmann::json::parse(test::readFile(store / "terrain" / "layer.json"));
  for (const auto& entry : fs::recursive_directory_iterator(store / "terrain")) {
    if (entry.path().extension() != ".terrain") continue;
    const fs::path rel = fs::relative(entry.path(), store / "terrain");
    auto it = rel.begin();
    TerrainTile t;
    t.id.z = std::stoi((it++)->string());
    t.id.x = static_cast<std::uint32_t>(std::stoul((it++)->string()));
    t.id.y = static_cast<std::uint32_t>(std::stoul(it->stem().string()));
    t.bounds = tiles::geographicTileBounds(t.id);
    const std::string bytes = test::readFile(entry.path());
    t.bytes = bytes.size();
    t.mesh = test::decodeQuantizedMesh(bytes);
    EXPECT_TRUE(t.mesh.ok) << rel << ": not read to its end exactly";
    t.record = tiles::recordFromExtras(metadataOf(t.mesh).dump()).value();
    out.tiles.push_back(std::move(t));
  }
  std::sort(out.tiles.begin(), out.tiles.end(),
            [](const auto& a, const auto& b) { return tiles::rowMajorLess(a.id, b.id); });
  return out;
}

fs::path makeTin(const fs::path& dir, const std::string& inputs, const std::string& crs) {
  const fs::path tin = dir / "t.tin";
  const auto r = test::runTinsmith("tin " + inputs + " --crs " + crs + " -q -o " + tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return tin;
}

struct TerrainRun {
  TerrainStore store;
  nlohmann::json summary;  ///< tinsmith tile --json's "terrain"
};

TerrainRun tileTerrain(const fs::path& tin, const fs::path& store, const std::string& flags) {
  const auto r = test::runTinsmith("tile " + tin.string() + " --scheme quantized-mesh -q --json " +
                                   flags + " -o " + store.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  TerrainRun run;
  run.summary = nlohmann::json::parse(r.out).at("terrain");
  run.store = readTerrainStore(store);
  return run;
}

/// layer.json's "available" as a set of tiles.
std::set<std::tuple<int, std::uint32_t, std::uint32_t>> availableTiles(
    const nlohmann::json& available, int firstLevel = 0) {
  std::set<std::tuple<int, std::uint32_t, std::uint32_t>> out;
  for (std::size_t level = 0; level < available.size(); ++level) {
    for (const auto& r : available[level]) {
      for (std::uint32_t y = r["startY"]; y <= r["endY"].get<std::uint32_t>(); ++y)
        for (std::uint32_t x = r["startX"]; x <= r["endX"].get<std::uint32_t>(); ++x)
          out.emplace(firstLevel + int(level), x, y);
    }
  }
  return out;
}

/// The store's structure: availability, parents, metadata, edge lists, the
/// header's sphere, the records.
void expectAWellFormedStore(const TerrainStore& store) {
  std::set<std::tuple<int, std::uint32_t, std::uint32_t>> stored;
  for (const auto& t : store.tiles) stored.emplace(t.id.z, t.id.x, t.id.y);
  EXPECT_EQ(availableTiles(store.layer.at("available")), stored)
      << "layer.json's available ranges are not the tiles stored";
  EXPECT_TRUE(stored.count({0, 0, 0}) && stored.count({0, 1, 0})) << "both level-0 tiles";
  int deepest = 0;
  for (const auto& t : store.tiles) {
    deepest = std::max(deepest, t.id.z);
    if (t.id.z > 0) {
      EXPECT_TRUE(stored.count({t.id.z - 1, t.id.x / 2, t.id.y / 2}))
          << t.id.name() << " has no parent: CesiumJS never reaches it";
    }
  }
  EXPECT_EQ(store.layer.at("maxzoom").get<int>(), deepest);
  EXPECT_EQ(store.layer.at("format"), "quantized-mesh-1.0");
  EXPECT_EQ(store.layer.at("scheme"), "tms");

  for (const auto& t : store.tiles) {
    const auto& m = t.mesh;
    const std::string name = t.id.name();
    ASSERT_FALSE(m.u.empty()) << name;
    EXPECT_EQ(t.record.id, t.id) << name << ": its metadata names another tile";
    EXPECT_EQ(t.record.vertices, m.u.size()) << name;
    EXPECT_EQ(t.record.triangles * 3, m.indices.size()) << name;
    // The edge lists are exactly the vertices on each side.
    const std::array<std::function<bool(std::size_t)>, 4> onSide = {
        [&](std::size_t i) { return m.u[i] == 0; }, [&](std::size_t i) { return m.v[i] == 0; },
        [&](std::size_t i) { return m.u[i] == encode::kQuantizedMax; },
        [&](std::size_t i) { return m.v[i] == encode::kQuantizedMax; }};
    for (int side = 0; side < 4; ++side) {
      std::set<std::uint32_t> expected, listed(m.edges[side].begin(), m.edges[side].end());
      for (std::size_t i = 0; i < m.u.size(); ++i)
        if (onSide[side](i)) expected.insert(static_cast<std::uint32_t>(i));
      EXPECT_EQ(listed, expected) << name << " side " << side;
      EXPECT_EQ(listed.size(), m.edges[side].size()) << name << " side " << side << ": repeats";
    }
    // The header's sphere holds every vertex; min and max heights are the vertices'.
    const Point3 c{m.sphereCentre[0], m.sphereCentre[1], m.sphereCentre[2]};
    double low = 1e300, high = -1e300;
    for (std::size_t i = 0; i < m.u.size(); ++i) {
      const encode::Geodetic g = t.vertex(i);
      const Point3 p = encode::geodeticToEcef(g);
      EXPECT_LE(std::hypot(p.x - c.x, p.y - c.y, p.z - c.z), m.sphereRadius * (1 + 1e-9) + 1e-3)
          << name << " vertex " << i;
      low = std::min(low, g.height);
      high = std::max(high, g.height);
    }
    EXPECT_NEAR(low, m.minHeight, 1e-3) << name;
    EXPECT_NEAR(high, m.maxHeight, 1e-3) << name;
  }
  // A level-0 tile's metadata lists the tiles of the ten levels below it.
  for (const auto& t : store.tiles) {
    if (t.id.z != 0) continue;
    const auto metadata = metadataOf(t.mesh);
    std::set<std::tuple<int, std::uint32_t, std::uint32_t>> below, listed;
    for (const auto& u : store.tiles)
      if (u.id.z >= 1 && u.id.z <= 10 && (u.id.x >> u.id.z) == t.id.x)
        below.emplace(u.id.z, u.id.x, u.id.y);
    if (metadata.contains("available")) listed = availableTiles(metadata["available"], 1);
    EXPECT_EQ(listed, below) << t.id.name() << "'s metadata availability";
  }
}

/// An oct-encoded unit vector (quantized-mesh's octvertexnormals), decoded
/// as the format's text gives it.
Point3 octDecode(std::uint8_t ou, std::uint8_t ov) {
  double x = ou / 255.0 * 2 - 1, y = ov / 255.0 * 2 - 1;
  const double z = 1 - std::abs(x) - std::abs(y);
  if (z < 0) {
    const double ox = x;
    x = (1 - std::abs(y)) * (ox >= 0 ? 1 : -1);
    y = (1 - std::abs(ox)) * (y >= 0 ? 1 : -1);
  }
  const double l = std::sqrt(x * x + y * y + z * z);
  return {x / l, y / l, z / l};
}

struct SurfaceCheck {
  std::size_t points = 0;  ///< measured: vertices and chord middles over the TIN
  std::size_t filled = 0;  ///< vertices of the fill (the ellipsoid outside the TIN)
  std::map<int, double> worstByLevel;
};

/// The decoded surface against the TIN: 3-D distances in the project CRS
/// (the TIN's z are ellipsoidal heights), as a tile's error bounds them
/// (docs/tile-error.md) — on a wall, quantization's metres sideways are
/// hundreds vertically. The fill — the ellipsoid,
/// height 0, where the TIN does not reach — and the walls down to it are not
/// the TIN's and are not measured: a vertex is the fill's when its decoded
/// height is within the quantization of 0 (every TIN here is far above 0).
SurfaceCheck expectTheSurfaceWithinItsErrors(const TerrainRun& run, const TinData& tin) {
  const tiles::TinIndex index(tin);
  const test::ToProject toProject(tin.crs);
  std::set<std::string> missed;
  for (const auto& m : run.summary.at("overError")) missed.insert(m.at("tile"));
  SurfaceCheck check;
  for (const auto& t : run.store.tiles) {
    const auto& m = t.mesh;
    const double levelError = tiles::cesiumLevelMaximumGeometricError(t.id.z);
    const std::string name = t.id.name();
    if (!missed.count(name)) {
      EXPECT_LE(t.record.error, levelError) << name << " is over CesiumJS's error for its level "
                                            << "and the summary does not say so";
    }
    std::vector<encode::Geodetic> g(m.u.size());
    std::vector<bool> fill(m.u.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
      g[i] = t.vertex(i);
      fill[i] = std::abs(g[i].height) <= t.heightHalfStep() * 2 + 1e-6;
      if (fill[i]) ++check.filled;
    }
    double worst = 0;
    // The project CRS's scale against the ground's metres (UTM: 0.9996), and
    // the frames' curvature (terrain_tiling.hpp).
    const double slack = 2e-3 + 1e-3 * t.record.error;
    std::vector<std::uint32_t> scratch;
    auto measure = [&](const encode::Geodetic& p, const char* what) {
      const Point3 q = toProject(p);
      const auto z = index.z({q.x, q.y});
      if (!z) return;  // off the TIN: a wall's top vertex rounded outward
      // The vertical distance bounds the 3-D one: the TIN is searched that far.
      const double off = test::distanceToTin(q, index, std::abs(q.z - *z) + 1.0, scratch).value();
      worst = std::max(worst, off);
      ++check.points;
      EXPECT_LE(off, t.record.error + slack)
          << name << " " << what << " at " << p.lon << ", " << p.lat << ": " << off
          << " m from the TIN, declared " << t.record.error;
    };
    for (std::size_t i = 0; i < g.size(); ++i)
      if (!fill[i]) measure(g[i], "vertex");
    // The fill is the ellipsoid, lit as the ground: a wall's foot too (its
    // normal is the fill's, not bent towards the wall).
    const std::string& normals = m.extensions.at(encode::kOctVertexNormals);
    EXPECT_EQ(normals.size(), 2 * m.u.size()) << name;
    for (std::size_t i = 0; i < g.size() && normals.size() == 2 * m.u.size(); ++i) {
      if (!fill[i]) continue;
      const Point3 n = octDecode(static_cast<std::uint8_t>(normals[2 * i]),
                                 static_cast<std::uint8_t>(normals[2 * i + 1]));
      const double lon = g[i].lon * std::numbers::pi / 180, lat = g[i].lat * std::numbers::pi / 180;
      const Point3 up{std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
      EXPECT_GT(n.x * up.x + n.y * up.y + n.z * up.z, std::cos(5 * std::numbers::pi / 180))
          << name << ": the ground at " << g[i].lon << ", " << g[i].lat << " is not lit as level";
    }
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
      const std::uint32_t a = m.indices[k], b = m.indices[k + 1], c = m.indices[k + 2];
      if (fill[a] || fill[b] || fill[c]) continue;
      for (auto [i, j] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) {
        const Point3 p = encode::geodeticToEcef(g[i]), q = encode::geodeticToEcef(g[j]);
        measure(encode::ecefToGeodetic({(p.x + q.x) / 2, (p.y + q.y) / 2, (p.z + q.z) / 2}),
                "chord middle");
      }
    }
    check.worstByLevel[t.id.z] = std::max(check.worstByLevel[t.id.z], worst);
  }
  return check;
}

/// Tiles of one level that share a side have the same vertices along it.
std::size_t expectSharedSidesToMatch(const TerrainStore& store) {
  std::map<std::tuple<int, std::uint32_t, std::uint32_t>, const TerrainTile*> byId;
  for (const auto& t : store.tiles) byId[{t.id.z, t.id.x, t.id.y}] = &t;
  std::size_t sides = 0;
  // Along a side: (the position along it, the decoded height), ascending.
  auto along = [](const TerrainTile& t, int side, bool vertical) {
    std::vector<std::pair<std::uint16_t, double>> out;
    for (const std::uint32_t i : t.mesh.edges[side])
      out.emplace_back(vertical ? t.mesh.v[i] : t.mesh.u[i], t.vertex(i).height);
    std::sort(out.begin(), out.end());
    return out;
  };
  for (const auto& t : store.tiles) {
    const std::uint32_t columns = 2u << t.id.z;
    for (const bool east : {true, false}) {
      const auto key = east ? std::tuple{t.id.z, (t.id.x + 1) % columns, t.id.y}
                            : std::tuple{t.id.z, t.id.x, t.id.y + 1};
      const auto other = byId.find(key);
      if (other == byId.end()) continue;
      const auto mine = along(t, east ? 2 : 3, east);
      const auto theirs = along(*other->second, east ? 0 : 1, east);
      ++sides;
      EXPECT_EQ(mine.size(), theirs.size())
          << t.id.name() << " and " << other->second->id.name() << " differ along their side";
      if (mine.size() != theirs.size()) continue;
      const double slack = t.heightHalfStep() + other->second->heightHalfStep() + 1e-6;
      for (std::size_t k = 0; k < mine.size(); ++k) {
        EXPECT_EQ(mine[k].first, theirs[k].first)
            << t.id.name() << " / " << other->second->id.name();
        EXPECT_NEAR(mine[k].second, theirs[k].second, slack)
            << t.id.name() << " / " << other->second->id.name() << " at " << mine[k].first;
      }
    }
  }
  return sides;
}

TEST(TerrainTiles, RedButteDecodesWithinEveryLevelsErrorWithSharedSidesAndItsLake) {
  const fs::path dir = test::scratchDir("terrain-red-butte");
  const fs::path tinPath = dir / "rb.tin";
  auto r = test::runTinsmith("tin " + std::string(TINSMITH_SOURCE_DIR) +
                             "/config/red-butte.toml -q -o " + tinPath.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const TerrainRun run = tileTerrain(tinPath, dir / "store", "--tolerance 5");
  expectAWellFormedStore(run.store);
  const TinData tin = readTinFile(tinPath);
  const SurfaceCheck check = expectTheSurfaceWithinItsErrors(run, tin);
  EXPECT_GT(check.points, 10000u);
  EXPECT_GT(check.filled, 0u) << "the tiles reach past the TIN, where the ellipsoid is";
  EXPECT_GE(expectSharedSidesToMatch(run.store), 10u);
  // The finest level is the first whose error is within 5 m (level 14: 4.70 m).
  EXPECT_EQ(run.summary.at("finestLevel"), 14);
  EXPECT_EQ(run.store.layer.at("maxzoom"), 14);
  EXPECT_TRUE(run.summary.at("overError").empty());
  // The reservoir is water in the tiles over it, the rest land.
  std::size_t water = 0, mixed = 0;
  for (const auto& t : run.store.tiles) {
    const std::string& mask = t.mesh.extensions.at(encode::kWaterMask);
    ASSERT_TRUE(mask.size() == 1 || mask.size() == 65536) << t.id.name();
    const auto wet = std::count(mask.begin(), mask.end(), char(255));
    if (wet > 0) ++water;
    if (wet > 0 && wet < static_cast<long>(mask.size())) ++mixed;
    EXPECT_EQ(std::count(mask.begin(), mask.end(), char(0)) + wet, static_cast<long>(mask.size()));
  }
  EXPECT_GT(mixed, 0u) << "no tile has the reservoir's shore";
  EXPECT_LT(water, run.store.tiles.size());
}

TEST(TerrainTiles, AMesasWallsAreWithinTheDeclaredErrorAtEveryLevel) {
  const fs::path dir = test::scratchDir("terrain-mesa");
  // A mesa: its rim at 1500 m (r = 250 m), its foot at 1000 m one metre out,
  // flat ground at 500 m to r = 500 m.
  const fs::path tinPath = makeTin(
      dir,
      "--breaklines "
      "'synthetic:rings?n=1&width=1000&height=1000&z0=1000&interval=500&x0=500000&y0=4500000' "
      "'synthetic:rings?n=1&width=1004&height=1004&z0=500&interval=500&x0=499998&y0=4499998' "
      "'synthetic:rings?n=1&width=2000&height=2000&z0=500&interval=500&x0=499500&y0=4499500'",
      "EPSG:32612");
  const TerrainRun run = tileTerrain(tinPath, dir / "store", "--tolerance 0.5 --max-triangles 256");
  expectAWellFormedStore(run.store);
  const SurfaceCheck check = expectTheSurfaceWithinItsErrors(run, readTinFile(tinPath));
  EXPECT_GT(check.points, 1000u);
  expectSharedSidesToMatch(run.store);
  EXPECT_EQ(run.summary.at("finestLevel"), 18);  // 0.29 m
}

TEST(TerrainTiles, APitAndALargeFlatPlainAreWithinTheirErrors) {
  const fs::path dir = test::scratchDir("terrain-pit-plain");
  // A 40 km plain at 800 m with a pit 300 m deep and 20 m wide in it.
  const fs::path tinPath = makeTin(
      dir,
      "--points 'synthetic:grid?nx=41&ny=41&spacing=1000&x0=380000&y0=4480000&surface=flat&z0=800' "
      "--breaklines "
      "'synthetic:rings?n=1&width=20&height=20&z0=500&interval=300&x0=400000&y0=4500000' "
      "'synthetic:rings?n=1&width=24&height=24&z0=800&interval=300&x0=399998&y0=4499998'",
      "EPSG:32633");
  const TerrainRun run = tileTerrain(tinPath, dir / "store", "--tolerance 1");
  expectAWellFormedStore(run.store);
  const SurfaceCheck check = expectTheSurfaceWithinItsErrors(run, readTinFile(tinPath));
  EXPECT_GT(check.points, 1000u);
  EXPECT_GE(expectSharedSidesToMatch(run.store), 4u);
  // The pit is reached: the deepest level's worst decoded distance is within
  // the finest level's error (1 m asked: level 17, 0.59 m) although the pit
  // is 300 m deep.
  const int finest = run.summary.at("finestLevel");
  const auto& [deepest, worst] = *check.worstByLevel.rbegin();
  EXPECT_LE(deepest, finest);
  EXPECT_LE(worst, tiles::cesiumLevelMaximumGeometricError(finest)) << "level " << deepest;
}

TEST(TerrainTiles, ATinAcrossTheAntimeridianIsTiledOnBothSides) {
  const fs::path dir = test::scratchDir("terrain-antimeridian");
  // UTM 60N at 50° N: 180° is about 215 km east of the central meridian
  // (177° E). A 30 km hill across it.
  const fs::path tinPath = makeTin(
      dir,
      "--points "
      "'synthetic:grid?nx=61&ny=61&spacing=500&x0=700000&y0=5525000&surface=hill&z0=200&scale=900'",
      "EPSG:32660");
  const TerrainRun run = tileTerrain(tinPath, dir / "store", "--tolerance 5");
  expectAWellFormedStore(run.store);
  const SurfaceCheck check = expectTheSurfaceWithinItsErrors(run, readTinFile(tinPath));
  EXPECT_GT(check.points, 1000u);
  EXPECT_GE(expectSharedSidesToMatch(run.store), 4u);
  // Tiles at the far west and the far east of the grid, at the finest level.
  const int finest = run.summary.at("finestLevel");
  const std::uint32_t columns = 2u << finest;
  bool west = false, east = false;
  for (const auto& t : run.store.tiles) {
    if (t.id.z != finest) continue;
    west |= t.id.x == 0;
    east |= t.id.x == columns - 1;
  }
  EXPECT_TRUE(west && east) << "the finest level should hold tiles on both sides of 180°";
  // bounds: west > east across the antimeridian, as a region crossing it is.
  const auto& b = run.store.layer.at("bounds");
  EXPECT_GT(b[0].get<double>(), 179.0);
  EXPECT_LT(b[2].get<double>(), -179.0);
}

std::map<std::string, std::string> filesUnder(const fs::path& root) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file()) out[fs::relative(e.path(), root).string()] = test::readFile(e.path());
  return out;
}

TEST(TerrainTiles, OneThreadOrTwoAResumedRunOrARebuildWriteTheSameBytes) {
  const fs::path dir = test::scratchDir("terrain-same-bytes");
  const fs::path tinPath = makeTin(
      dir, "--points 'synthetic:grid?nx=31&ny=31&spacing=200&x0=430000&y0=4510000&surface=franke'",
      "EPSG:26912");
  const std::string tile =
      "tile " + tinPath.string() + " --scheme quantized-mesh --tolerance 2 -q ";
  ASSERT_EQ(test::runTinsmith(tile + "--threads 1 -o " + (dir / "one").string()).exitCode, 0);
  ASSERT_EQ(test::runTinsmith(tile + "--threads 2 -o " + (dir / "two").string()).exitCode, 0);
  const auto one = filesUnder(dir / "one");
  ASSERT_GT(one.size(), 20u);
  EXPECT_TRUE(one == filesUnder(dir / "two")) << "another thread count, other bytes";

  // A run stopped before its deepest level and layer.json, then resumed.
  const int deepest = nlohmann::json::parse(one.at("terrain/layer.json")).at("maxzoom");
  fs::remove_all(dir / "two" / "terrain" / std::to_string(deepest));
  fs::remove(dir / "two" / "terrain" / "layer.json");
  const auto info = test::runTinsmith("info " + (dir / "two").string());
  EXPECT_NE(info.out.find("incomplete: no terrain/layer.json"), std::string::npos) << info.out;
  const auto resumed = test::runTinsmith(tile + "--resume --json -o " + (dir / "two").string());
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  const auto summary = nlohmann::json::parse(resumed.out).at("terrain");
  EXPECT_GT(summary.at("kept").get<int>(), 0);
  EXPECT_GT(summary.at("built").get<int>(), 0);
  EXPECT_EQ(summary.at("built").get<int>() + summary.at("kept").get<int>(),
            summary.at("tiles").get<int>());
  EXPECT_TRUE(one == filesUnder(dir / "two")) << "resumed, other bytes";

  // Built again over itself (it is a store tinsmith wrote), and described.
  ASSERT_EQ(test::runTinsmith(tile + "-o " + (dir / "two").string()).exitCode, 0);
  EXPECT_TRUE(one == filesUnder(dir / "two"));
  const auto described = test::runTinsmith("info --json " + (dir / "two").string());
  ASSERT_EQ(described.exitCode, 0) << described.err;
  EXPECT_EQ(nlohmann::json::parse(described.out).at("terrain").at("tiles").get<std::size_t>(),
            one.size() - 3);  // less layer.json, build.json and the TIN
}

TEST(TerrainTiles, ATinAroundAPoleIsRefusedAndLeavesNoStore) {
  const fs::path dir = test::scratchDir("terrain-pole");
  const fs::path tinPath = makeTin(
      dir,
      "--points 'synthetic:grid?nx=11&ny=11&spacing=2000&x0=-10000&y0=-10000&surface=hill&z0=100'",
      "EPSG:3995");
  const auto r = test::runTinsmith("tile " + tinPath.string() + " --scheme quantized-mesh -q -o " +
                                   (dir / "store").string());
  EXPECT_EQ(r.exitCode, 4) << r.err;
  EXPECT_NE(r.err.find("pole"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "store"));
}

}  // namespace
}  // namespace tinsmith::ingest
