// The demo's pyramid (config/red-butte.toml: contours, spot heights, a road,
// streams, the reservoir, the boundary; its [tiles] tolerance): every zoom's
// neighbouring tiles share their side vertices bit for bit (no cracks within
// a zoom, also where a break line crosses a side), every tile's measured
// error meets its zoom's tolerance where the budget allowed, and no river
// rises downstream in any tile.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>

#include "core/tiles/tiler.hpp"
#include "ingest/build/from_ingest.hpp"
#include "ingest/config/project_config.hpp"

namespace tinsmith {
namespace {

using tiles::TileId;
using tiles::TileSurface;

std::vector<std::tuple<double, double, double>> sideVertices(const TileSurface& t,
                                                             std::uint8_t side) {
  std::vector<std::tuple<double, double, double>> out;
  for (std::size_t v = 0; v < t.vertices.size(); ++v) {
    if (t.flags[v] & side) out.emplace_back(t.vertices[v].x, t.vertices[v].y, t.vertices[v].z);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(DemoTiles, SharedSidesAreBitForBitAndEveryZoomMeetsItsTolerance) {
  const auto config = ingest::loadProjectConfig(std::filesystem::path(TINSMITH_SOURCE_DIR) /
                                                "config/red-butte.toml");
  TinData tin;
  ingest::buildTinFromConfig(config, ingest::buildOptionsFrom(config),
                             [&](const Mesh& mesh) { tin = mesh.toTinData(); });
  tiles::TilerOptions options;
  options.tolerance = 2.5;  // three zooms, so sides are shared at two of them
  options.maxZoom = 4;
  const tiles::Tiler tiler(tin, options);

  // The pyramid as the job walks it: a tile's four children where it refines.
  std::map<TileId, TileSurface> built;
  std::vector<TileId> todo{{0, 0, 0}};
  while (!todo.empty()) {
    const TileId id = todo.back();
    todo.pop_back();
    TileSurface tile = tiler.buildTile(id);
    if (tile.empty()) continue;
    if (tiler.refines(id, tile.error, tile.error)) {
      for (int i = 0; i < 4; ++i) todo.push_back(id.child(i));
    }
    built.emplace(id, std::move(tile));
  }
  ASSERT_GE(built.size(), 5u);
  // Where a river feature of the TIN ends (a source, a mouth, a confluence).
  std::set<std::pair<double, double>> riverEnds;
  {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> degree;  // (feature, vertex)
    for (const auto& e : tin.constrainedEdges) {
      if (tin.features[e.feature].kind != FeatureKind::River) continue;
      ++degree[{e.feature, e.a}];
      ++degree[{e.feature, e.b}];
    }
    for (const auto& [key, d] : degree) {
      if (d == 1) riverEnds.insert({tin.vertices[key.second].x, tin.vertices[key.second].y});
    }
  }
  std::size_t pairs = 0, riverVertices = 0;
  for (const auto& [id, tile] : built) {
    if (tile.triangles.size() < options.maxTriangles) {
      EXPECT_LE(tile.error, tiler.zoomTolerance(id.z)) << "tile " << id.name();
    }
    // East and north neighbours of the same zoom.
    for (const auto& [dx, dy, mine, theirs] :
         {std::tuple{1u, 0u, tiles::kSideEast, tiles::kSideWest},
          std::tuple{0u, 1u, tiles::kSideNorth, tiles::kSideSouth}}) {
      const auto it = built.find({id.z, id.x + dx, id.y + dy});
      if (it == built.end()) continue;
      ++pairs;
      EXPECT_EQ(sideVertices(tile, mine), sideVertices(it->second, theirs))
          << "tiles " << id.name() << " and " << it->first.name();
    }
    // No river rises downstream: a river vertex between two river neighbours
    // (away from the TIN rivers' ends) lies between their heights.
    std::map<std::uint32_t, std::set<std::uint32_t>> river;
    for (std::size_t t = 0; t < tile.triangles.size(); ++t) {
      for (int i = 0; i < 3; ++i) {
        if (!((tile.riverEdges[t] >> i) & 1U)) continue;
        const std::uint32_t a = tile.triangles[t][i], b = tile.triangles[t][(i + 1) % 3];
        river[a].insert(b);
        river[b].insert(a);
      }
    }
    for (const auto& [v, next] : river) {
      const Point3& p = tile.vertices[v];
      if (next.size() != 2 || riverEnds.count({p.x, p.y})) continue;
      ++riverVertices;
      const double za = tile.vertices[*next.begin()].z, zb = tile.vertices[*next.rbegin()].z;
      EXPECT_LE(p.z, std::max(za, zb) + 1e-9)
          << "a river rises in tile " << id.name() << " at (" << p.x << ", " << p.y << ")";
      EXPECT_GE(p.z, std::min(za, zb) - 1e-9)
          << "a river rises in tile " << id.name() << " at (" << p.x << ", " << p.y << ")";
    }
  }
  EXPECT_GT(riverVertices, 0u);
  EXPECT_GE(pairs, 4u) << "no two tiles of one zoom to compare: the test sees nothing";
}

}  // namespace
}  // namespace tinsmith
