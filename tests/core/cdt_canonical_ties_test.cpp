// CdtOptions::canonicalTies: cocircular ties broken by a symbolic lift, so the
// mesh is a function of the input alone. Grids are all ties; the mesh must
// not depend on the points' order, the two-halves split or the threads, and
// must stay Delaunay (the validator) — while without the option the same
// inputs do give different meshes, so the cases below can tell.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;

using Triangle = std::array<Point2, 3>;

bool lessXY(const Point2& a, const Point2& b) {
  return a.x < b.x || (a.x == b.x && a.y < b.y);
}

/// The triangles as sorted corner triples, sorted: the mesh without its numbering.
std::vector<Triangle> triangleSet(const TinData& tin) {
  std::vector<Triangle> out;
  for (const auto& t : tin.triangles) {
    Triangle c;
    for (int i = 0; i < 3; ++i) c[i] = {tin.vertices[t[i]].x, tin.vertices[t[i]].y};
    std::sort(c.begin(), c.end(), lessXY);
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [](const Triangle& a, const Triangle& b) {
    return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), lessXY);
  });
  return out;
}

struct Way {
  bool canonical = true;
  std::size_t splitMin = 0;
  unsigned threads = 1;
  std::uint32_t shuffleSeed = 0;  ///< 0: the points as given
};

std::vector<Triangle> build(std::vector<Point3> points, const Way& way,
                            const std::vector<std::vector<Point3>>& lines = {}) {
  if (way.shuffleSeed != 0) {
    std::mt19937 rng(way.shuffleSeed);
    std::shuffle(points.begin(), points.end(), rng);
  }
  CdtOptions options;
  options.canonicalTies = way.canonical;
  options.splitMinPoints = way.splitMin;
  options.threads = way.threads;
  Cdt cdt(options);
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "roads");
  cdt.insertPoints(points);
  for (const auto& line : lines) cdt.insertConstraint(line, road);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  return triangleSet(cdt.toTinData());
}

std::vector<Point3> grid(int n, double x0, double y0, double step) {
  std::vector<Point3> points;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) points.push_back({x0 + i * step, y0 + j * step, double(i ^ j)});
  return points;
}

/// The ways a mesh was built that must all agree with the option, and that
/// do not all agree without it.
const std::vector<Way> kWays = {{true, 0, 1, 0},   {true, 0, 1, 7},   {true, 0, 1, 99},
                                {true, 300, 1, 0}, {true, 300, 2, 5}, {true, 300, 2, 11}};

void expectOrderFree(const std::vector<Point3>& points,
                     const std::vector<std::vector<Point3>>& lines = {}) {
  const auto reference = build(points, kWays.front(), lines);
  for (const Way& way : kWays) {
    EXPECT_EQ(build(points, way, lines), reference)
        << "split " << way.splitMin << ", threads " << way.threads << ", shuffle "
        << way.shuffleSeed;
  }
  bool differs = false;
  for (Way way : kWays) {
    way.canonical = false;
    differs = differs || build(points, way, lines) != reference;
  }
  EXPECT_TRUE(differs)
      << "without canonicalTies every way gave the same mesh: the case tests nothing";
}

TEST(CdtCanonicalTies, ASquaresDiagonalAvoidsItsLeastPoint) {
  // Both orders of the same square; the least point by (x, y) is (0, 0).
  for (const bool reversed : {false, true}) {
    std::vector<Point3> square{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    if (reversed) std::reverse(square.begin(), square.end());
    const auto triangles = build(square, {});
    ASSERT_EQ(triangles.size(), 2u);
    for (const Triangle& t : triangles) {
      const bool hasOrigin = t[0] == Point2{0, 0};
      const bool hasFarCorner = t[2] == Point2{1, 1};
      EXPECT_FALSE(hasOrigin && hasFarCorner) << "the diagonal (0,0)-(1,1) touches the least point";
    }
  }
}

TEST(CdtCanonicalTies, AGridDoesNotDependOnOrderSplitOrThreads) {
  expectOrderFree(grid(40, 0, 0, 1));
}

TEST(CdtCanonicalTies, AGridAtUtmCoordinatesToo) {
  expectOrderFree(grid(30, 487123.25, 5012345.5, 0.5));
}

TEST(CdtCanonicalTies, PointsOnOneCircleInsideAGrid) {
  // The twelve integer points on the circle of radius 5 (ties of twelve
  // points at once) inside a grid cut open around them.
  std::vector<Point3> points = grid(14, -6.5, -6.5, 1);
  points.erase(std::remove_if(points.begin(), points.end(),
                              [](const Point3& p) { return std::hypot(p.x, p.y) < 5.5; }),
               points.end());
  for (const auto& [x, y] : {std::pair{5.0, 0.0}, {-5.0, 0.0}, {0.0, 5.0}, {0.0, -5.0}})
    points.push_back({x, y, 1});
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      points.push_back({3 * sx, 4 * sy, 2});
      points.push_back({4 * sx, 3 * sy, 2});
    }
  expectOrderFree(points);
}

TEST(CdtCanonicalTies, ConstraintsStayAndTheRestIsOrderFree) {
  const std::vector<std::vector<Point3>> lines = {{{0.5, 0.5, 1}, {20.5, 14.5, 1}},
                                                  {{3, 17, 2}, {17, 3, 2}}};
  expectOrderFree(grid(24, 0, 0, 1), lines);
}

}  // namespace
}  // namespace tinsmith
