// Tiles: the lines kept per zoom, the exact surface difference and section,
// and tiles of a small synthetic TIN (shared sides bit for bit and on the
// TIN, break lines held, the finest zoom within its tolerance, determinism).
// The demo pyramid's quality is checked by the CLI tests and the JS checkers.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/mesh/mesh.hpp"
#include "core/surface/surface.hpp"
#include "core/tiles/chord_sag.hpp"
#include "core/tiles/pyramid.hpp"
#include "core/tiles/surface_difference.hpp"
#include "core/tiles/terrain_lines.hpp"
#include "core/tiles/tile_mosaic.hpp"
#include "core/tiles/tile_refiner.hpp"
#include "core/tiles/tiler.hpp"
#include "core/tin/hull_trim.hpp"
#include "tests/support/test_terrain.hpp"

namespace tinsmith::tiles {
namespace {

using test::hill;
using test::rippledRiverTin;

/// A 1 km square of jittered points on a hill with a road across it, at
/// UTM-sized coordinates.
TinData syntheticTin() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-8, 8);
  std::vector<Point3> points;
  const double x0 = 500000, y0 = 4500000;
  for (int j = 0; j <= 25; ++j) {
    for (int i = 0; i <= 25; ++i) {
      const double x = i * 40.0 + ((i > 0 && i < 25) ? jitter(rng) : 0);
      const double y = j * 40.0 + ((j > 0 && j < 25) ? jitter(rng) : 0);
      points.push_back({x0 + x, y0 + y, hill(x, y)});
    }
  }
  cdt.insertPoints(points, spots);
  std::vector<Point3> line;
  for (int k = 0; k <= 20; ++k) {
    const double x = 30 + k * 47.0, y = 120 + k * 38.0 + 10 * std::sin(k);
    line.push_back({x0 + x, y0 + y, hill(x, y) + 0.5});
  }
  cdt.insertConstraint(line, road);
  cdt.finalize();
  return cdt.toTinData();
}

TEST(TerrainLines, DouglasPeuckerKeepsTheEndsAndWhatIsFarEnough) {
  TerrainLine line;
  line.points = {{0, 0, 0}, {1, 0.001, 0}, {2, 0, 0}, {3, 5, 0}, {4, 0, 0}};
  const TerrainLine s = simplify(line, 0.1);
  ASSERT_EQ(s.points.size(), 4u);
  EXPECT_EQ(s.points.front(), line.points.front());
  EXPECT_EQ(s.points.back(), line.points.back());
  EXPECT_EQ(s.points[2], line.points[3]);
}

TEST(TerrainLines, ACrossingIsTheSameDoubleFromBothSidesOfATileSide) {
  // The same segment, clipped by the two tiles that share x = 10.
  TerrainLine ab, ba;
  ab.points = {{3.1, 1.7, 5}, {17.3, 8.9, 9}};
  ba.points = {ab.points[1], ab.points[0]};
  const Rect west{0, 0, 10, 10}, east{10, 0, 20, 10};
  const auto w = clipToRect(ab, west, 1e-9);
  const auto e = clipToRect(ba, east, 1e-9);
  ASSERT_EQ(w.size(), 1u);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(w[0].points.back(), e[0].points.back());
  EXPECT_EQ(w[0].points.back().x, 10.0);
}

TEST(TerrainLines, BreakLinesAndTheBoundaryRingComeOutOfATin) {
  const TinData tin = syntheticTin();
  const auto lines = extractTerrainLines(tin);
  int roads = 0, rings = 0;
  for (const auto& l : lines) {
    roads += l.kind == FeatureKind::Road;
    rings += l.ring;
  }
  EXPECT_GE(roads, 1);
  EXPECT_EQ(rings, 1);
}

TEST(TerrainLines, BoundaryHalfEdgesAreThoseAHalfEdgeMeshLeavesWithoutATwin) {
  // What the rings are traced from, against the half-edge mesh's own
  // boundary, on TINs with holes, pinched holes, duplicated, overturned,
  // non-manifold and invalid triangles.
  const auto meshBoundary = [](const TinData& tin) {
    const Mesh mesh = Mesh::fromTinData(tin);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    for (HalfedgeId h : mesh.boundaryHalfedges())
      out.push_back({mesh.origin(h).value, mesh.target(h).value});
    std::sort(out.begin(), out.end());
    return out;
  };
  TinData lone;
  lone.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  lone.triangles = {{0, 1, 2}};
  EXPECT_EQ(boundaryHalfEdges(lone),
            (std::vector<std::pair<std::uint32_t, std::uint32_t>>{{0, 1}, {1, 2}, {2, 0}}));
  EXPECT_EQ(boundaryHalfEdges(syntheticTin()), meshBoundary(syntheticTin()));

  // A 7 × 7 grid of vertices, each cell cut into two CCW triangles.
  TinData grid;
  const std::uint32_t n = 7;
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i) grid.vertices.push_back({double(i), double(j), 0});
  for (std::uint32_t j = 0; j + 1 < n; ++j)
    for (std::uint32_t i = 0; i + 1 < n; ++i) {
      const std::uint32_t a = j * n + i;
      grid.triangles.push_back({a, a + 1, a + n + 1});
      grid.triangles.push_back({a, a + n + 1, a + n});
    }
  const auto without = [&](std::vector<std::size_t> drop) {
    TinData t = grid;
    std::sort(drop.rbegin(), drop.rend());
    for (const std::size_t k : drop)
      t.triangles.erase(t.triangles.begin() + static_cast<std::ptrdiff_t>(k));
    return t;
  };
  std::vector<TinData> cases;
  cases.push_back(grid);
  cases.push_back(without({14, 15, 16, 17}));          // a hole
  cases.push_back(without({14, 15, 28, 29, 30, 31}));  // two holes meeting at a vertex
  cases.push_back(without({0, 11, 12}));               // notches in the hull
  TinData duplicated = grid;                           // edges used twice one way
  duplicated.triangles.push_back(grid.triangles[20]);
  cases.push_back(duplicated);
  TinData overturned = grid;  // a reversed copy: three triangles at its edges
  const auto& t20 = grid.triangles[20];
  overturned.triangles.push_back({t20[0], t20[2], t20[1]});
  cases.push_back(overturned);
  TinData invalid = grid;  // dropped by both: a repeated corner, one out of range
  invalid.triangles.push_back({3, 3, 4});
  invalid.triangles.push_back({3, 4, 4000});
  cases.push_back(invalid);
  std::mt19937_64 rng(11);
  for (int k = 0; k < 20; ++k) {  // a third of the triangles gone at random
    TinData t;
    t.vertices = grid.vertices;
    for (const auto& tri : grid.triangles)
      if (rng() % 3 != 0) t.triangles.push_back(tri);
    cases.push_back(t);
  }
  for (std::size_t c = 0; c < cases.size(); ++c) {
    SCOPED_TRACE("case " + std::to_string(c));
    const auto expected = meshBoundary(cases[c]);
    EXPECT_EQ(boundaryHalfEdges(cases[c]), expected);
    if (c == 1) {
      EXPECT_EQ(expected.size(), 4 * (n - 1) + 6);  // the hull and a 2 × 1 hole
    }
  }
}

TEST(SurfaceDifference, PeakOfAPyramidOverAPlaneIsFoundExactly) {
  // TIN: a square pyramid with its apex 1 m up, off the mesh's vertices.
  TinData tin;
  tin.vertices = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {3.3, 6.1, 1.0}};
  tin.triangles = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  const TinIndex index(tin);
  const std::vector<Point3> mesh = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}};
  const std::vector<std::array<std::uint32_t, 3>> triangles = {{0, 1, 2}, {0, 2, 3}};
  const auto d = maxVerticalDifference(mesh, triangles, index);
  EXPECT_NEAR(d.maxAbs, 1.0, 1e-12);
  EXPECT_NEAR(d.at.x, 3.3, 1e-9);
  EXPECT_NEAR(d.at.y, 6.1, 1e-9);
}

TEST(SurfaceDifference, NeverBelowADenseSampleOfTheDifference) {
  const TinData tin = syntheticTin();
  const TinIndex index(tin);
  // A coarse mesh: the TIN's bounding square in 8 triangles, z from a plane.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const auto& v : tin.vertices) {
    x0 = std::min(x0, v.x), y0 = std::min(y0, v.y), x1 = std::max(x1, v.x), y1 = std::max(y1, v.y);
  }
  std::vector<Point3> mesh;
  for (int j = 0; j <= 2; ++j)
    for (int i = 0; i <= 2; ++i) {
      const double x = x0 + (x1 - x0) * i / 2, y = y0 + (y1 - y0) * j / 2;
      mesh.push_back({x, y, 100 + 0.01 * (x - x0)});
    }
  std::vector<std::array<std::uint32_t, 3>> triangles;
  for (std::uint32_t j = 0; j < 2; ++j)
    for (std::uint32_t i = 0; i < 2; ++i) {
      const std::uint32_t a = j * 3 + i;
      triangles.push_back({a, a + 1, a + 4});
      triangles.push_back({a, a + 4, a + 3});
    }
  const auto declared = maxVerticalDifference(mesh, triangles, index);
  // Brute force: the difference at the TIN's vertices and on a fine grid.
  const Surface tinSurface(tin);
  const Surface meshSurface(TinData{"", mesh, {triangles.begin(), triangles.end()}, {}, {}});
  double sampled = 0;
  auto probe = [&](Point2 p) {
    const auto a = tinSurface.z(p), b = meshSurface.z(p);
    if (a && b) sampled = std::max(sampled, std::abs(*a - *b));
  };
  for (const auto& v : tin.vertices) probe(v.xy());
  for (int j = 0; j <= 200; ++j)
    for (int i = 0; i <= 200; ++i) probe({x0 + (x1 - x0) * i / 200, y0 + (y1 - y0) * j / 200});
  EXPECT_GE(declared.maxAbs, sampled - 1e-9);
  EXPECT_LE(declared.maxAbs, sampled + 0.05);  // the grid comes within its spacing of the peak
}

TEST(SurfaceDifference, TheSectionIsTheTinAlongTheSegment) {
  const TinData tin = syntheticTin();
  const TinIndex index(tin);
  const Surface surface(tin);
  const double x0 = 500000, y0 = 4500000;
  // Axis-parallel and oblique, one running off the TIN at both ends.
  const std::vector<std::pair<Point2, Point2>> segments{
      {{x0 + 3.5, y0 + 410.25}, {x0 + 977.0, y0 + 410.25}},
      {{x0 + 520.0, y0}, {x0 + 520.0, y0 + 1000.0}},
      {{x0 + 13.0, y0 + 21.0}, {x0 + 911.0, y0 + 777.0}},
      {{x0 - 50.0, y0 + 500.0}, {x0 + 1050.0, y0 + 500.0}}};
  std::vector<TinIndex::SectionPoint> section;
  for (const auto& [a, b] : segments) {
    index.section(a, b, section);
    ASSERT_GE(section.size(), 10u);
    auto at = [&](double t) { return Point2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; };
    for (std::size_t k = 0; k < section.size(); ++k) {
      if (k > 0) {
        EXPECT_GE(section[k].t, section[k - 1].t);
      }
      if (std::isnan(section[k].z)) continue;
      const auto z = surface.z(at(section[k].t));
      ASSERT_TRUE(z.has_value());
      EXPECT_NEAR(section[k].z, *z, 1e-9);
    }
    // Linear between consecutive points: the TIN at any t in between.
    for (std::size_t k = 0; k + 1 < section.size(); ++k) {
      const auto [t0, z0] = section[k];
      const auto [t1, z1] = section[k + 1];
      if (std::isnan(z0) || std::isnan(z1) || t1 - t0 < 1e-9) continue;
      for (double w : {0.25, 0.5, 0.75}) {
        const auto z = surface.z(at(t0 + w * (t1 - t0)));
        ASSERT_TRUE(z.has_value());
        EXPECT_NEAR(z0 + w * (z1 - z0), *z, 1e-8);
      }
    }
  }
  // Off the TIN: the stretches before and after the TIN are not covered.
  index.section(segments[3].first, segments[3].second, section);
  EXPECT_GT(section.front().t, 0.04);
  EXPECT_LT(section.back().t, 0.96);
  EXPECT_EQ(index.z({x0 - 1, y0 + 500}), std::nullopt);
  EXPECT_NEAR(*index.z({x0 + 400, y0 + 600}), *surface.z({x0 + 400, y0 + 600}), 1e-9);
}

TEST(SurfaceDifference, SectionsThroughLongSlantedSliversMissNoTriangle) {
  // A ring of vertices 4 m apart round a few far inside and a square far
  // outside, as a mesa's contours over spot heights: slivers kilometres long
  // at every slant, each listed only in the index cells it comes near. A
  // triangle left out of a cell a segment crosses would show as a gap or as
  // a stretch that is not the TIN.
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::SpotHeight, "ring");
  const double x0 = 500000, y0 = 4500000, cx = x0 + 1500, cy = y0 + 1500;
  auto height = [&](double x, double y) {
    return 100 + 0.01 * (x - x0) + 3e-5 * (y - y0) * (y - y0);
  };
  std::vector<Point3> points;
  for (int k = 0; k < 1600; ++k) {
    const double a = 2 * std::numbers::pi * k / 1600, r = 1000 + 30 * std::sin(7 * a);
    points.push_back({cx + r * std::cos(a), cy + r * std::sin(a), 0});
  }
  for (int k = 0; k < 5; ++k) points.push_back({cx + 40.0 * k - 80, cy + 17.0 * (k % 3), 0});
  for (const double x : {x0, x0 + 3000}) {
    for (const double y : {y0, y0 + 3000}) points.push_back({x, y, 0});
  }
  for (auto& p : points) p.z = height(p.x, p.y);
  cdt.insertPoints(points, f);
  cdt.finalize();
  const TinData tin = cdt.toTinData();
  const TinIndex index(tin);
  const Surface surface(tin);
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(0, 3000);
  std::vector<TinIndex::SectionPoint> section;
  for (int s = 0; s < 300; ++s) {
    const Point2 a{x0 + u(rng), y0 + u(rng)}, b{x0 + u(rng), y0 + u(rng)};
    index.section(a, b, section);
    auto at = [&](double t) { return Point2{a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)}; };
    ASSERT_FALSE(section.empty());
    EXPECT_EQ(section.front().t, 0.0);
    EXPECT_EQ(section.back().t, 1.0);
    for (std::size_t k = 0; k + 1 < section.size(); ++k) {
      const auto [t0, z0] = section[k];
      const auto [t1, z1] = section[k + 1];
      ASSERT_FALSE(std::isnan(z0)) << "a gap inside the TIN, segment " << s;
      if (t1 - t0 < 1e-9) continue;
      for (double w : {0.25, 0.5, 0.75}) {
        const auto z = surface.z(at(t0 + w * (t1 - t0)));
        ASSERT_TRUE(z.has_value());
        EXPECT_NEAR(z0 + w * (z1 - z0), *z, 1e-7) << "segment " << s << " at t " << t0;
      }
    }
    const Point2 p = at(0.37);
    EXPECT_NEAR(*index.z(p), *surface.z(p), 1e-7);
  }
}

TEST(Tiles, ThePlanningFitOverSquaresChoosesTheFinestZoomOfTheWholeFit) {
  // Over more fit points than planningCellPoints the planning fit runs over
  // the squares of a zoom, one at a time (its memory a square's): their
  // finest levels hold nearly the whole fit's triangles (a few fewer: no
  // square refines beside its neighbour to keep the whole triangulation
  // conforming), and choose the same finest zoom unless the whole fit's
  // count lies that close to the count a zoom allows. 14 400 points of rough
  // ground over 4 squares of 3 600, and 4 800 of a strip over 4 squares, of
  // which 2 hold nothing.
  const auto rough = [](double x, double y) {
    return 100 + 20 * std::sin(x / 90) * std::cos(y / 70) + 5 * std::sin(x / 13 + y / 17);
  };
  const auto grid = [&](int rows) {
    Cdt cdt;
    const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> jitter(-2, 2);
    std::vector<Point3> points;
    for (int j = 0; j < rows; ++j) {
      for (int i = 0; i < 120; ++i) {
        const double x = i * 10.0 + jitter(rng), y = j * 10.0 + jitter(rng);
        points.push_back({500000 + x, 4500000 + y, rough(x, y)});
      }
    }
    cdt.insertPoints(points, spots);
    cdt.finalize();
    return cdt.toTinData();
  };
  const TinData square = grid(120), strip = grid(40);
  for (const TinData* t : {&square, &strip}) {
    for (const double tolerance : {0.5, 2.0, 5.0}) {
      SCOPED_TRACE(std::string(t == &square ? "the square" : "the strip") + " at tolerance " +
                   std::to_string(tolerance));
      TilerOptions options;
      options.tolerance = tolerance;
      options.maxTriangles = 1024;
      options.threads = 1;
      const Tiler whole(*t, options);
      options.planningCellPoints = 3600;
      const Tiler squares(*t, options);
      EXPECT_EQ(whole.planningCellZoom(), 0);
      EXPECT_EQ(squares.planningCellZoom(), 1);
      const double a = static_cast<double>(whole.planningTriangles());
      const double b = static_cast<double>(squares.planningTriangles());
      EXPECT_GT(a, 1000);
      EXPECT_LE(b, a);
      // Where the fit goes to the data's own spacing (more triangles than
      // points: the square at 0.5 m, 23 583 triangles) the squares' may
      // hold a fifth fewer (19 192 here); coarser, within a few %.
      const bool toTheData = a > static_cast<double>(t->vertices.size());
      EXPECT_GT(b, (toTheData ? 0.75 : 0.95) * a) << b << " against " << a;
      bool nearABound = false;
      for (int z = 0; z <= 10; ++z)
        nearABound |= std::abs(a / (256.0 * std::pow(4.0, z)) - 1) < 0.05;
      if (!nearABound) {
        EXPECT_EQ(squares.finestZoom(), whole.finestZoom()) << b << " against " << a;
      }
    }
  }
  // A raster's last row on a square's side lies alone in the squares above
  // it, on one line, where a fit is singular: those squares are left out.
  {
    Cdt cdt;
    const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
    std::vector<Point3> points;
    for (int j = 0; j <= 20; ++j) {
      for (int i = 0; i <= 40; ++i)
        points.push_back({i * 10.0, j * 10.0, rough(i * 10.0, j * 10.0)});
    }
    cdt.insertPoints(points, spots);
    cdt.finalize();
    const TinData raster = cdt.toTinData();  // 400 m × 200 m: its top row at y = 200
    TilerOptions options;
    options.tolerance = 0.5;
    options.maxTriangles = 256;
    options.threads = 1;
    options.planningCellPoints = 200;
    const Tiler squares(raster, options);
    EXPECT_EQ(squares.planningCellZoom(), 2);  // 100 m squares: the top row alone in row 2
    EXPECT_GT(squares.planningTriangles(), 0u);
  }
  // A plan's finest zoom runs no planning fit.
  TilerOptions given;
  given.plannedFinestZoom = 2;
  EXPECT_EQ(Tiler(square, given).planningCellZoom(), -1);
}

TEST(Tiles, TheFinestZoomMeetsTheToleranceAndSidesLieOnTheTin) {
  const TinData tin = syntheticTin();
  const Surface surface(tin);
  for (const double tolerance : {0.05, 0.2}) {
    TilerOptions options;
    options.tolerance = tolerance;
    options.maxTriangles = 4096;
    const Tiler tiler(tin, options);
    const int z = tiler.finestZoom();
    const std::uint32_t n = 1u << z;
    std::size_t built = 0, sides = 0, exact = 0;
    for (std::uint32_t y = 0; y < n; ++y) {
      for (std::uint32_t x = 0; x < n; ++x) {
        const TileSurface t = tiler.buildTile({z, x, y});
        if (t.empty()) continue;
        ++built;
        EXPECT_LE(t.error, tolerance)
            << "tile " << t.id.name() << " at tolerance " << tolerance << ": " << t.heldPoints
            << " TIN points held, " << t.triangles.size() << " triangles";
        // A side vertex is the TIN's point there, or a road crossing within
        // the road's simplification (which stays within 0.4 of the tolerance).
        for (std::size_t v = 0; v < t.vertices.size(); ++v) {
          if (!(t.flags[v] & 15)) continue;
          const auto zt = surface.z(t.vertices[v].xy());
          if (!zt) continue;
          ++sides;
          if (std::abs(t.vertices[v].z - *zt) <= 1e-9) ++exact;
          EXPECT_NEAR(t.vertices[v].z, *zt, 0.4 * tolerance + 1e-9);
        }
      }
    }
    EXPECT_GE(built, 1u);
    EXPECT_GE(exact * 10, sides * 9) << exact << " of " << sides << " side vertices exact";
  }
}

// The top of a pyramid fitted to the mosaic of a zoom's tiles instead of
// the TIN (issue 24): the tiles join without a crack, keep the river, the
// road and the hole, and a tile above fitted to them, refined to its
// tolerance less E (the mosaic's own error) and declaring its error against
// the mosaic plus E, is within that declaration against the TIN itself.
TEST(TileMosaic, TheTopFittedToAZoomsTilesKeepsItsDeclarationAgainstTheTin) {
  const TinData tin = rippledRiverTin();
  TilerOptions options;
  options.tolerance = 0.05;
  options.maxTriangles = 4096;
  const Tiler tiler(tin, options);
  constexpr int k = 2;
  ASSERT_GE(tiler.finestZoom(), k);  // each zoom above twice zoom k's tolerance
  std::vector<TileSurface> zoomK;
  std::size_t tileVertices = 0;
  for (std::uint32_t y = 0; y < (1U << k); ++y)
    for (std::uint32_t x = 0; x < (1U << k); ++x) {
      zoomK.push_back(tiler.buildTile({k, x, y}));
      tileVertices += zoomK.back().vertices.size();
    }
  const TileMosaic mosaic = mosaicOf(zoomK, tin.crs);
  EXPECT_LT(mosaic.tin.vertices.size(), tileVertices);  // the sides are shared
  double e = 0;
  std::size_t triangles = 0;
  for (const TileSurface& t : zoomK) {
    e = std::max(e, t.error);
    triangles += t.triangles.size();
  }
  EXPECT_EQ(mosaic.maxError, e);
  EXPECT_EQ(mosaic.tin.triangles.size(), triangles);
  // No crack: the mosaic's boundary is the square's outline, which is the
  // TIN's, and the hole's.
  const Rect square = tiler.geometry().bounds({});
  const Rect hole{square.x0 + 120, square.y0 + 120, square.x0 + 200, square.y0 + 200};
  const auto alongSides = [](const Rect& r, const Point3& a, const Point3& b) {
    return (a.x == r.x0 && b.x == r.x0) || (a.x == r.x1 && b.x == r.x1) ||
           (a.y == r.y0 && b.y == r.y0) || (a.y == r.y1 && b.y == r.y1);
  };
  const auto boundary = boundaryHalfEdges(mosaic.tin);
  std::size_t holeEdges = 0;
  for (const auto& [a, b] : boundary) {
    const Point3& p = mosaic.tin.vertices[a];
    const Point3& q = mosaic.tin.vertices[b];
    holeEdges += alongSides(hole, p, q);
    EXPECT_TRUE(alongSides(square, p, q) || alongSides(hole, p, q))
        << p.x << " " << p.y << " → " << q.x << " " << q.y;
  }
  EXPECT_GE(holeEdges, 4u);
  // The river and the road as the tiles keep them, and the two rings.
  const auto lines = extractTerrainLines(mosaic.tin);
  const auto count = [&](auto&& pred) { return std::count_if(lines.begin(), lines.end(), pred); };
  EXPECT_EQ(count([](const auto& l) { return l.ring; }), 2);
  EXPECT_GE(count([](const auto& l) { return l.kind == FeatureKind::River; }), 1);
  EXPECT_GE(count([](const auto& l) { return !l.ring && l.kind == FeatureKind::BreakLine; }), 1);
  // Its lines are inside it: no ring's edge (the boundary's) is one.
  std::set<std::pair<std::uint32_t, std::uint32_t>> boundaryEdges;
  for (const auto& [a, b] : boundary) boundaryEdges.insert({std::min(a, b), std::max(a, b)});
  std::set<std::uint32_t> features;
  for (const auto& c : mosaic.tin.constrainedEdges) {
    features.insert(c.feature);
    EXPECT_FALSE(boundaryEdges.contains({c.a, c.b})) << c.a << " " << c.b;
  }
  EXPECT_EQ(features, (std::set<std::uint32_t>{0, 1}));

  TilerOptions top = options;
  top.fixed = TilerOptions::FixedPyramid{tiler.geometry(), tiler.finestZoom(), k};
  top.maxZoom = tiler.maxZoom();
  top.mosaicError = [&](const TileId&) { return e; };
  const Tiler topTiler(mosaic.tin, top);
  top.mosaicError = {};
  const Tiler againstTheMosaic(mosaic.tin, top);
  const TinIndex index(tin);
  for (const TileId id : {TileId{0, 0, 0}, TileId{1, 0, 0}, TileId{1, 1, 1}}) {
    SCOPED_TRACE(id.name());
    const TileSurface s = topTiler.buildTile(id);
    ASSERT_FALSE(s.empty());
    EXPECT_LE(s.error, tiler.zoomTolerance(id.z));
    EXPECT_LE(maxVerticalDifference(s.vertices, s.triangles, index).maxAbs, s.error + 1e-9);
    // Refined further than the same tile against the mosaic alone, and
    // declaring the mosaic's error besides its own.
    const TileSurface plain = againstTheMosaic.buildTile(id);
    EXPECT_GT(s.triangles.size(), plain.triangles.size());
    EXPECT_GE(s.error, e);
  }
}

// Regression: a DEM with nodata, its TIN's hull trimmed, so the domain's
// boundary runs along the raster's rows and columns — as the tile sides do,
// within rounding (both are whole cells from its corner; the cell 26.477 m
// is not a binary fraction). A ring vertex an ulp off a side made a sliver
// along the side measured 212 m off on Red Butte's DEM, and a tile corner on
// the TIN's boundary took the fit's z instead of the TIN's (11 m off).
TEST(Tiles, ARastersBoundaryAlongTheTileSidesMeetsTheTolerance) {
  Cdt cdt;
  const FeatureId cells = cdt.addFeature(FeatureKind::SpotHeight, "dem");
  const double x0 = 430580.446, y0 = 4512454.755, cell = 26.477018;
  std::vector<Point3> points;
  for (int j = 0; j <= 40; ++j) {
    for (int i = 0; i <= 40; ++i) {
      if (i > 20 && j > 20) continue;  // nodata: an L-shaped footprint
      const double x = i * cell, y = j * cell;
      points.push_back({x0 + x, y0 + y, 1800 + 0.2 * x + 40 * std::sin(x / 90) * std::cos(y / 70)});
    }
  }
  cdt.insertPoints(points, cells);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  ASSERT_GT(trimHull(tin, 3 * cell), 0u);
  TilerOptions options;
  options.tolerance = 1.0;
  options.maxTriangles = 4096;
  options.maxZoom = 2;
  const Tiler tiler(tin, options);
  std::size_t built = 0;
  for (int z = 0; z <= 2; ++z) {
    const std::uint32_t n = 1u << z;
    for (std::uint32_t y = 0; y < n; ++y) {
      for (std::uint32_t x = 0; x < n; ++x) {
        const TileSurface t = tiler.buildTile({z, x, y});
        if (t.empty()) continue;
        ++built;
        if (t.triangles.size() >= options.maxTriangles) continue;  // stopped by the budget
        EXPECT_LE(t.error, tiler.zoomTolerance(z))
            << "tile " << t.id.name() << " at (" << t.errorAt.x - x0 << ", " << t.errorAt.y - y0
            << ")";
      }
    }
  }
  EXPECT_GE(built, 4u);
}

TEST(Tiles, NeighboursShareTheirSideVerticesBitForBit) {
  const TinData tin = syntheticTin();
  TilerOptions options;
  options.tolerance = 0.5;
  options.maxTriangles = 2048;
  const Tiler tiler(tin, options);
  for (int z = 1; z <= 2; ++z) {
    const std::uint32_t n = 1u << z;
    std::map<std::tuple<int, std::uint32_t, std::uint32_t>, TileSurface> tiles;
    for (std::uint32_t y = 0; y < n; ++y)
      for (std::uint32_t x = 0; x < n; ++x) tiles[{z, x, y}] = tiler.buildTile({z, x, y});
    auto sideVertices = [](const TileSurface& t, std::uint8_t side) {
      std::vector<std::tuple<double, double, double>> out;
      for (std::size_t v = 0; v < t.vertices.size(); ++v)
        if (t.flags[v] & side) out.push_back({t.vertices[v].x, t.vertices[v].y, t.vertices[v].z});
      std::sort(out.begin(), out.end());
      return out;
    };
    for (std::uint32_t y = 0; y < n; ++y) {
      for (std::uint32_t x = 0; x + 1 < n; ++x) {
        const auto& w = tiles[{z, x, y}];
        const auto& e = tiles[{z, x + 1, y}];
        if (w.empty() || e.empty()) continue;
        EXPECT_EQ(sideVertices(w, kSideEast), sideVertices(e, kSideWest))
            << "zoom " << z << " x " << x << " y " << y;
      }
    }
    for (std::uint32_t y = 0; y + 1 < n; ++y) {
      for (std::uint32_t x = 0; x < n; ++x) {
        const auto& s = tiles[{z, x, y}];
        const auto& nn = tiles[{z, x, y + 1}];
        if (s.empty() || nn.empty()) continue;
        EXPECT_EQ(sideVertices(s, kSideNorth), sideVertices(nn, kSideSouth)) << "zoom " << z;
      }
    }
  }
}

TEST(Tiles, BreakLineVerticesKeepTheTinsHeightAndTilesArePure) {
  const TinData tin = syntheticTin();
  TilerOptions options;
  options.tolerance = 0.5;
  options.maxTriangles = 2048;
  const Tiler tiler(tin, options);
  std::map<std::pair<double, double>, double> roadZ;
  for (const auto& e : tin.constrainedEdges) {
    if (tin.features[e.feature].kind != FeatureKind::Road) continue;
    for (auto v : {e.a, e.b}) roadZ[{tin.vertices[v].x, tin.vertices[v].y}] = tin.vertices[v].z;
  }
  std::size_t held = 0;
  for (std::uint32_t y = 0; y < 4; ++y) {
    for (std::uint32_t x = 0; x < 4; ++x) {
      const TileSurface t = tiler.buildTile({2, x, y});
      for (const auto& v : t.vertices) {
        auto it = roadZ.find({v.x, v.y});
        if (it == roadZ.end()) continue;
        EXPECT_EQ(v.z, it->second);
        ++held;
      }
      const TileSurface again = tiler.buildTile({2, x, y});
      EXPECT_EQ(t.vertices, again.vertices);
      EXPECT_EQ(t.triangles, again.triangles);
      EXPECT_EQ(t.error, again.error);
      if (!t.empty()) {
        EXPECT_GE(t.error, 0.0);
      }
    }
  }
  EXPECT_GE(held, 2u);
}

// Cliffs: dense contours on a wall beside sparse ones on a plain put the
// median edge at metres and the plain's triangles at hundreds; each of those
// got a 64-step grid of samples (a 127 k-vertex mesa: 17 M fit points,
// 2.9 GB). The samples stay within the TIN's vertex count.
TEST(Tiles, FitSamplesStayWithinTheTinsVertexCount) {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  std::vector<Point3> points;
  const double x0 = 500000, y0 = 4500000;
  for (int j = 0; j <= 10; ++j)  // the plain: 10 km at 1 km
    for (int i = 0; i <= 10; ++i) points.push_back({x0 + i * 1000.0, y0 + j * 1000.0, 100.0 + i});
  for (int j = 0; j < 60; ++j)  // the wall: 60 m × 60 m at 1 m, 50 m high
    for (int i = 0; i < 60; ++i)
      points.push_back(
          {x0 + 4200 + i * 1.0 + 0.3 * (j % 2), y0 + 4200 + j * 1.0, 100.0 + 50.0 * (i > 30)});
  cdt.insertPoints(points, spots);
  cdt.finalize();
  const TinData tin = cdt.toTinData();
  TilerOptions options;
  options.tolerance = 1;
  const Tiler tiler(tin, options);
  EXPECT_GT(tiler.dataPointCount(), tin.vertices.size());  // the plain is sampled
  EXPECT_LE(tiler.dataPointCount(), 2 * tin.vertices.size());
}

TEST(ChordSag, TheDeepestPointOfAFlatTriangleUnderASphere) {
  const double R = 6.4e6;
  // A plane through points of a sphere lies r²/2R below it at most (to second
  // order), r the circumradius, when the circumcentre is inside.
  const double L = 6000;
  const ChordSag equilateral = chordSag({0, 0}, {L, 0}, {L / 2, L * std::sqrt(3.0) / 2}, R);
  EXPECT_NEAR(equilateral.depth, L * L / 3 / (2 * R), 1e-12);
  EXPECT_NEAR(equilateral.at.x, L / 2, 1e-9);
  EXPECT_NEAR(equilateral.at.y, L / (2 * std::sqrt(3.0)), 1e-9);
  // Right or obtuse: at the middle of the longest edge, L²/8R.
  const ChordSag right = chordSag({0, 0}, {L, 0}, {0, L}, R);
  EXPECT_NEAR(right.depth, 2 * L * L / (8 * R), 1e-12);
  EXPECT_NEAR(right.at.x, L / 2, 1e-9);
  EXPECT_NEAR(right.at.y, L / 2, 1e-9);
  const ChordSag sliver = chordSag({0, 0}, {L, 0}, {L / 2, 1}, R);
  EXPECT_NEAR(sliver.depth, L * L / (8 * R), 1e-12);
  // The same from the edges' middles: their sags l²/8R, taken over the
  // triangle as the quadratic they are.
  auto mid = [&](double l2) { return l2 / (8 * R); };
  EXPECT_NEAR(quadraticGapMax(mid(L * L), mid(L * L), mid(L * L)), equilateral.depth, 1e-12);
  EXPECT_NEAR(quadraticGapMax(mid(L * L), mid(2 * L * L), mid(L * L)), right.depth, 1e-12);
  EXPECT_NEAR(quadraticGapMax(mid(L * L), 0.0, 0.0), mid(L * L), 1e-15);
}

TEST(Tiles, BadOptionsAreUsageErrors) {
  const TinData tin = syntheticTin();
  TilerOptions options;
  options.tolerance = 0;
  EXPECT_THROW(Tiler(tin, options), tinsmith::Error);
  options.tolerance = -1;
  EXPECT_THROW(Tiler(tin, options), tinsmith::Error);
  options.tolerance = 1;
  options.maxTriangles = 10;
  EXPECT_THROW(Tiler(tin, options), tinsmith::Error);
  EXPECT_THROW(parseTileId("3/8/0", "--subtree"), tinsmith::Error);
  EXPECT_THROW(parseTileId("a/b/c", "--subtree"), tinsmith::Error);
  EXPECT_EQ(parseTileId("3/7/1", "--subtree"), (TileId{3, 7, 1}));
}

TEST(TileRefiner, AnErrorInsideTheSideMarginEndsItsTriangleNotTheBudget) {
  // Regression (issue 21, the mesa at tolerance 2): a TIN vertex closer to a
  // tile side than the margin, 9 m off the mesh, in a triangle whose top at
  // that x lies below the margin line. The point brought in to the margin
  // was outside the triangle, so its nearest edge was split at the foot, the
  // error stayed where it was, and the next split came closer, every split
  // flipping the growing fan of the side's corner: 8.4 M flips, a gigabyte of
  // heap and edge cache and 60 s in one zoom-1 tile, stopped only by the
  // triangle budget.
  TinData tin;
  tin.vertices = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {0, 100, 0}, {30, 1, 10}};
  tin.triangles = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  const TinIndex index(tin);
  TileSurface tile;
  tile.id = {0, 0, 0};
  tile.bounds = {0, 0, 100, 100};
  // The sides at the TIN (flat), and a held vertex on the margin line.
  tile.vertices = {{0, 0, 0}, {100, 0, 0}, {100, 100, 0}, {0, 100, 0}, {60, 5, *index.z({60, 5})}};
  tile.flags = {kSideSouth | kSideWest | kHeld, kSideSouth | kSideEast | kHeld,
                kSideNorth | kSideEast | kHeld, kSideNorth | kSideWest | kHeld, kHeld | kPinned};
  tile.triangles = {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  tile.heldEdges = {1, 1, 1, 1};
  tile.riverEdges = {0, 0, 0, 0};
  RefineOptions options;
  options.tolerance = 1;
  options.maxTriangles = 2000;
  options.sideMargin = 5;
  const std::size_t inserted = refineTile(tile, index, options);
  EXPECT_LT(inserted, 50U);
  EXPECT_LT(tile.triangles.size(), 100U);
  // What is left over the tolerance is declared: the exact error of the mesh.
  const SurfaceDifference exact = maxVerticalDifference(tile.vertices, tile.triangles, index);
  EXPECT_GT(exact.maxAbs, options.tolerance);
  EXPECT_DOUBLE_EQ(tile.error, exact.maxAbs);
}

}  // namespace
}  // namespace tinsmith::tiles
