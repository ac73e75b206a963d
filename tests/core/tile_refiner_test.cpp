// Greedy refinement of a tile mesh (core/tiles/tile_refiner.hpp): the tile
// meets its tolerance, the mesh stays a valid constrained Delaunay
// triangulation with its sides untouched, its declared error is the exact
// error of what it holds, a river keeps descending through the vertices it
// gains, and degenerate TINs (a cocircular grid, UTM-sized coordinates) work.
#include "core/tiles/tile_refiner.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/cdt/cdt.hpp"
#include "core/mesh/validate.hpp"
#include "core/tiles/surface_difference.hpp"

namespace tinsmith::tiles {
namespace {

constexpr double kX0 = 500000, kY0 = 4500000;  // UTM-sized
constexpr double kSize = 1000;

/// A rough surface with a valley along y = 500 (m, relative to the corner),
/// whose floor descends eastwards (curved, so a chord of it misses it) or,
/// `bumpyRiver`, rises and falls.
double terrain(double x, double y, bool bumpyRiver) {
  const double off = std::abs(y - 500) / 500;
  const double floor = bumpyRiver ? 100 + 4 * std::sin(x / 60) : 100 - 0.01 * x - 3e-6 * x * x;
  return floor + 20 * off +
         off * (6 * std::sin(x / 37) * std::cos(y / 53) + 3 * std::sin((x + y) / 11));
}

/// The TIN: an exact square grid (every cell's four corners cocircular).
TinData gridTin(int cells, bool bumpyRiver = false) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::SpotHeight, "grid");
  std::vector<Point3> points;
  const double step = kSize / cells;
  for (int j = 0; j <= cells; ++j) {
    for (int i = 0; i <= cells; ++i) {
      points.push_back({kX0 + i * step, kY0 + j * step, terrain(i * step, j * step, bumpyRiver)});
    }
  }
  cdt.insertPoints(points, f);
  cdt.finalize();
  return cdt.toTinData();
}

/// A coarse tile over the whole square: its sides (held at the TIN), a river
/// across it from west to east (its ends on the TIN; they descend unless the
/// TIN is bumpy there), and a few free vertices at a flat 100 m.
TileSurface coarseTile(const TinIndex& tin) {
  Cdt cdt;
  const FeatureId side = cdt.addFeature(FeatureKind::Other, "tile side");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
  const FeatureId free = cdt.addFeature(FeatureKind::Raster, "fit");
  // The sides through every TIN vertex on them (the grid's), so they are
  // the TIN's section, as the tiler makes them.
  std::vector<Point3> ring;
  const int pieces = 50;
  for (int k = 0; k < 4; ++k) {  // CCW from the south-west corner
    for (int s = 0; s < pieces; ++s) {
      const double u = s * kSize / pieces;
      const double x = k == 0 ? u : k == 1 ? kSize : k == 2 ? kSize - u : 0;
      const double y = k == 0 ? 0 : k == 1 ? u : k == 2 ? kSize : kSize - u;
      ring.push_back({kX0 + x, kY0 + y, *tin.z({kX0 + x, kY0 + y})});
    }
  }
  cdt.insertConstraint(ring, side, true);
  const double zWest = *tin.z({kX0 + 100, kY0 + 500}), zEast = *tin.z({kX0 + 900, kY0 + 500});
  cdt.insertConstraint(std::vector<Point3>{{kX0 + 100, kY0 + 500, std::max(zWest, zEast)},
                                           {kX0 + 900, kY0 + 500, std::min(zWest, zEast)}},
                       river);
  cdt.insertPoints(std::vector<Point3>{{kX0 + 300, kY0 + 250, 100},
                                       {kX0 + 700, kY0 + 250, 100},
                                       {kX0 + 300, kY0 + 750, 100},
                                       {kX0 + 700, kY0 + 750, 100}},
                   free);
  cdt.finalize();
  const Mesh& mesh = cdt.mesh();
  TileSurface tile;
  tile.bounds = {kX0, kY0, kX0 + kSize, kY0 + kSize};
  tile.vertices = mesh.points();
  tile.flags.assign(tile.vertices.size(), 0);
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
    const auto corners = mesh.vertices(TriangleId(t));
    std::uint8_t held = 0, rivers = 0;
    for (int i = 0; i < 3; ++i) {
      const HalfedgeId h = Mesh::halfedge(TriangleId(t), i);
      if (!mesh.isConstrained(h)) continue;
      held |= 1U << i;
      for (std::uint32_t f : mesh.edgeFeatures(h)) {
        if (f == river) rivers |= 1U << i;
      }
      tile.flags[mesh.origin(h).value] |= kHeld;
      tile.flags[mesh.target(h).value] |= kHeld;
    }
    tile.triangles.push_back({corners[0].value, corners[1].value, corners[2].value});
    tile.heldEdges.push_back(held);
    tile.riverEdges.push_back(rivers);
  }
  for (std::size_t v = 0; v < tile.vertices.size(); ++v) {
    const Point3& p = tile.vertices[v];
    if (p.x == kX0) tile.flags[v] |= kSideWest;
    if (p.x == kX0 + kSize) tile.flags[v] |= kSideEast;
    if (p.y == kY0) tile.flags[v] |= kSideSouth;
    if (p.y == kY0 + kSize) tile.flags[v] |= kSideNorth;
  }
  return tile;
}

/// The tile as TinData with its held edges as constraints (feature 0), for
/// the validator: CCW, manifold, constrained Delaunay.
TinData asTin(const TileSurface& tile) {
  TinData tin;
  tin.vertices = tile.vertices;
  tin.features.push_back({FeatureKind::Other, "held"});
  for (std::size_t t = 0; t < tile.triangles.size(); ++t) {
    tin.triangles.push_back(tile.triangles[t]);
    for (int i = 0; i < 3; ++i) {
      if (!((tile.heldEdges[t] >> i) & 1U)) continue;
      const std::uint32_t a = tile.triangles[t][i], b = tile.triangles[t][(i + 1) % 3];
      tin.constrainedEdges.push_back({std::min(a, b), std::max(a, b), 0});
    }
  }
  std::sort(tin.constrainedEdges.begin(), tin.constrainedEdges.end(),
            [](const auto& x, const auto& y) { return x.a < y.a || (x.a == y.a && x.b < y.b); });
  tin.constrainedEdges.erase(std::unique(tin.constrainedEdges.begin(), tin.constrainedEdges.end()),
                             tin.constrainedEdges.end());
  return tin;
}

std::vector<Point3> sideVertices(const TileSurface& tile) {
  std::vector<Point3> out;
  for (std::size_t v = 0; v < tile.vertices.size(); ++v) {
    if (tile.flags[v] & 15) out.push_back(tile.vertices[v]);
  }
  std::sort(out.begin(), out.end(), [](const Point3& a, const Point3& b) {
    return a.x < b.x || (a.x == b.x && a.y < b.y);
  });
  return out;
}

TEST(TileRefiner, MeetsTheToleranceWithAValidMeshAndTheExactError) {
  const TinData tinData = gridTin(50);
  const TinIndex tin(tinData);
  for (const double tolerance : {4.0, 1.0, 0.25}) {
    TileSurface tile = coarseTile(tin);
    const auto sidesBefore = sideVertices(tile);
    const std::size_t before = tile.triangles.size();
    RefineOptions options;
    options.tolerance = tolerance;
    options.maxTriangles = 100000;
    options.sideMargin = 1e-4 * kSize;
    const std::size_t added = refineTile(tile, tin, options);
    EXPECT_GT(added, 0u);
    EXPECT_GT(tile.triangles.size(), before);
    EXPECT_LE(tile.error, tolerance) << tile.triangles.size() << " triangles";
    // The declared error is the exact error of the refined mesh.
    const SurfaceDifference exact = maxVerticalDifference(tile.vertices, tile.triangles, tin);
    EXPECT_EQ(tile.error, exact.maxAbs);
    const ValidationReport report = validate(asTin(tile));
    EXPECT_TRUE(report.ok) << report.summary();
    EXPECT_EQ(report.boundaryLoops, 1u);
    // Sides are shared with the neighbours: not one vertex moved or added.
    EXPECT_EQ(sideVertices(tile), sidesBefore);
    ASSERT_EQ(tile.heldEdges.size(), tile.triangles.size());
    ASSERT_EQ(tile.riverEdges.size(), tile.triangles.size());
  }
}

TEST(TileRefiner, TheRiverKeepsDescendingThroughItsNewVertices) {
  const TinData tinData = gridTin(50, true);
  const TinIndex tin(tinData);
  TileSurface tile = coarseTile(tin);
  RefineOptions options;
  options.tolerance = 0.5;
  options.maxTriangles = 4000;
  options.sideMargin = 1e-4 * kSize;
  refineTile(tile, tin, options);
  // The river's vertices, west to east, from its edges.
  std::map<double, double> river;
  for (std::size_t t = 0; t < tile.triangles.size(); ++t) {
    for (int i = 0; i < 3; ++i) {
      if (!((tile.riverEdges[t] >> i) & 1U)) continue;
      for (const std::uint32_t v : {tile.triangles[t][i], tile.triangles[t][(i + 1) % 3]}) {
        river[tile.vertices[v].x] = tile.vertices[v].z;
      }
    }
  }
  ASSERT_GT(river.size(), 2u) << "the refinement split the river nowhere: the test sees nothing";
  double previous = HUGE_VAL;
  for (const auto& [x, z] : river) {
    EXPECT_LE(z, previous) << "the river rises at x = " << x - kX0;
    previous = z;
  }
}

TEST(TileRefiner, StopsAtTheTriangleBudgetAndSaysWhatItReached) {
  const TinData tinData = gridTin(50);
  const TinIndex tin(tinData);
  TileSurface tile = coarseTile(tin);
  RefineOptions options;
  options.tolerance = 1e-6;
  options.maxTriangles = 600;
  options.sideMargin = 1e-4 * kSize;
  refineTile(tile, tin, options);
  EXPECT_LE(tile.triangles.size(), 600u + 2);  // the last split adds at most 2 over
  EXPECT_GT(tile.error, options.tolerance);
  EXPECT_EQ(tile.error, maxVerticalDifference(tile.vertices, tile.triangles, tin).maxAbs);
  EXPECT_TRUE(validate(asTin(tile)).ok);
}

}  // namespace
}  // namespace tinsmith::tiles
