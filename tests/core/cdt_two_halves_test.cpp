// The first bulk of points may be triangulated as two halves merged along a
// seam (CdtOptions::splitMinPoints). The merged mesh must pass the validator
// on degenerate input, equal the one-go Delaunay triangulation where that is
// unique (points in general position), keep the merge semantics, and not
// depend on the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;
using testing::kSanitized;
using testing::randomPoints;

/// Small enough to split every case below (they have a few thousand points).
constexpr std::size_t kSplit = 1000;

struct Built {
  TinData tin;
  std::size_t merges = 0;
  std::size_t dropped = 0;
};

Built build(const std::vector<Point3>& points, std::size_t splitMin, unsigned threads = 1,
            double snap = 0.0, const std::vector<std::vector<Point3>>& lines = {}) {
  CdtOptions options;
  options.splitMinPoints = splitMin;
  options.threads = threads;
  options.snapTolerance = snap;
  Cdt cdt(options);
  const FeatureId spot = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "roads");
  cdt.insertPoints(points, spot);
  for (const auto& line : lines) cdt.insertConstraint(line, road);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  return {cdt.toTinData(), cdt.report().merges.size(), cdt.report().dropped.size()};
}

/// Triangles as sorted corner-coordinate triples (independent of vertex and
/// triangle numbering), sorted.
std::vector<std::array<Point2, 3>> canonical(const TinData& tin) {
  std::vector<std::array<Point2, 3>> out;
  auto less = [](const Point2& a, const Point2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); };
  for (const auto& t : tin.triangles) {
    std::array<Point2, 3> c;
    for (int i = 0; i < 3; ++i) c[i] = {tin.vertices[t[i]].x, tin.vertices[t[i]].y};
    std::sort(c.begin(), c.end(), less);
    out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [&](const auto& a, const auto& b) {
    return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), less);
  });
  return out;
}

TEST(CdtTwoHalves, GeneralPositionGivesTheUniqueDelaunayTriangulation) {
  // UTM-sized coordinates: 20 km × 20 km around (500 km, 4.5 Mm).
  std::vector<Point3> pts = randomPoints(kSanitized ? 3000 : 20000, 3, 0, 20000);
  for (Point3& p : pts) {
    p.x += 500000;
    p.y += 4500000;
  }
  const Built whole = build(pts, 0);
  const Built halves = build(pts, kSplit);
  EXPECT_EQ(whole.tin.vertices.size(), halves.tin.vertices.size());
  EXPECT_EQ(canonical(whole.tin), canonical(halves.tin));
}

TEST(CdtTwoHalves, CocircularGridIsDelaunay) {
  // Every quad of a regular grid is cocircular, and the seam runs along a
  // grid column.
  std::vector<Point3> pts;
  const int n = kSanitized ? 60 : 150;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) pts.push_back({i * 2.0, j * 2.0, 0.0});
  }
  const Built whole = build(pts, 0);
  const Built halves = build(pts, kSplit);
  EXPECT_EQ(halves.tin.vertices.size(), pts.size());
  EXPECT_EQ(halves.tin.triangles.size(), whole.tin.triangles.size());
}

TEST(CdtTwoHalves, PointsOnACircleAreAllSeam) {
  // Every circumcircle is the same circle and crosses the split line: no
  // triangle is safe, the seam triangulation is the whole one.
  std::vector<Point3> pts;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    pts.push_back({1000 * std::cos(a), 1000 * std::sin(a), 0.0});
  }
  const Built halves = build(pts, kSplit);
  EXPECT_EQ(halves.tin.triangles.size() + 2, halves.tin.vertices.size());
}

TEST(CdtTwoHalves, ManyPointsOnTheSplitColumn) {
  // Half the points share one x (the median): they all go to the right half.
  std::vector<Point3> pts = randomPoints(3000, 5, 0, 1000);
  for (int j = 0; j < 3000; ++j) pts.push_back({500.0, j / 3.0, 1.0});
  const Built whole = build(pts, 0);
  const Built halves = build(pts, kSplit);
  EXPECT_EQ(halves.tin.vertices.size(), whole.tin.vertices.size());
  EXPECT_EQ(halves.tin.triangles.size(), whole.tin.triangles.size());
}

TEST(CdtTwoHalves, CollinearHalfFallsBackToOneGo) {
  // The left half is a single line: it cannot be triangulated alone.
  std::vector<Point3> pts;
  for (int i = 0; i < 3000; ++i) pts.push_back({-1.0 - i, 0.5 * (-1.0 - i), 0.0});
  const std::vector<Point3> right = randomPoints(3000, 7, 0, 1000);
  pts.insert(pts.end(), right.begin(), right.end());
  const Built whole = build(pts, 0);
  const Built halves = build(pts, kSplit);
  EXPECT_EQ(canonical(whole.tin), canonical(halves.tin));
}

TEST(CdtTwoHalves, NoSnapGapNearTheMedianFallsBackToOneGo) {
  // x every 0.05 m with a 1 m snap tolerance: no left–right split can keep
  // every cross pair farther apart than the tolerance.
  std::vector<Point3> pts;
  for (int i = 0; i < 3000; ++i) pts.push_back({0.05 * i, 37.0 * (i % 7), 0.0});
  const Built whole = build(pts, 0, 1, 1.0);
  const Built halves = build(pts, kSplit, 1, 1.0);
  EXPECT_EQ(canonical(whole.tin), canonical(halves.tin));
  EXPECT_EQ(whole.merges, halves.merges);
}

TEST(CdtTwoHalves, DuplicatesAndSnapMergesAreKept) {
  // Clusters of exact and near duplicates (within the snap tolerance), far
  // apart from each other: the same merges as in one go, none across the seam.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002);
  std::vector<Point3> pts;
  for (const Point3& p : randomPoints(2500, 9, 0, 5000)) {
    pts.push_back(p);
    pts.push_back(p);
    pts.push_back({p.x + jitter(rng), p.y + jitter(rng), p.z + 1});
  }
  const Built whole = build(pts, 0, 1, 0.01);
  const Built halves = build(pts, kSplit, 1, 0.01);
  EXPECT_EQ(halves.merges, whole.merges);
  EXPECT_EQ(halves.tin.vertices.size(), whole.tin.vertices.size());
  EXPECT_EQ(halves.tin.vertices.size() * 3, pts.size());
  // Merge z by priority then input order: the kept z is the first of each
  // cluster's in both builds.
  auto zs = [](const TinData& tin) {
    std::vector<double> z;
    for (const Point3& p : tin.vertices) z.push_back(p.z);
    std::sort(z.begin(), z.end());
    return z;
  };
  EXPECT_EQ(zs(halves.tin), zs(whole.tin));
}

TEST(CdtTwoHalves, ConstraintsOnEachSideAndAcrossTheSeam) {
  // Disjoint segments (horizontal, at distinct heights): some left, some
  // right, some across the split line. The CDT is unique.
  const std::vector<Point3> pts = randomPoints(kSanitized ? 3000 : 10000, 13, 0, 1000);
  std::vector<std::vector<Point3>> lines;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> d(0, 1000), len(5, 300);
  for (int i = 0; i < 120; ++i) {
    const double x = d(rng), y = 2.0 + 8.0 * i;
    lines.push_back({{x, y, 5}, {std::min(999.0, x + len(rng)), y, 6}});
  }
  lines.push_back({{500, 1.0, 1}, {500, 999.0, 1}});  // along the seam
  const Built whole = build(pts, 0, 1, 0.0, lines);
  const Built halves = build(pts, kSplit, 1, 0.0, lines);
  EXPECT_EQ(canonical(whole.tin), canonical(halves.tin));
  EXPECT_EQ(whole.tin.constrainedEdges.size(), halves.tin.constrainedEdges.size());
}

TEST(CdtTwoHalves, CrossingConstraintsOnEachSideAndAcrossTheSeam) {
  // Crossings are computed in another order than in one go, so rounded
  // crossing points may differ in the last bits: compare what is counted.
  const std::vector<Point3> pts = randomPoints(kSanitized ? 3000 : 10000, 13, 0, 1000);
  std::vector<std::vector<Point3>> lines;
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> d(0, 1000), len(-150, 150);
  for (int i = 0; i < 200; ++i) {
    const double x = d(rng), y = d(rng);
    lines.push_back({{x, y, 5}, {std::clamp(x + len(rng), 0.0, 1000.0),
                                 std::clamp(y + len(rng), 0.0, 1000.0), 6}});
  }
  CdtOptions options;
  options.splitMinPoints = kSplit;
  auto crossings = [&](std::size_t splitMin) {
    options.splitMinPoints = splitMin;
    Cdt cdt(options);
    const FeatureId road = cdt.addFeature(FeatureKind::Road, "roads");
    cdt.insertPoints(pts);
    for (const auto& line : lines) cdt.insertConstraint(line, road);
    cdt.finalize();
    EXPECT_TRUE(isValid(cdt));
    return std::make_pair(cdt.report().intersections.size(), cdt.mesh().triangleCount());
  };
  const auto whole = crossings(0), halves = crossings(kSplit);
  EXPECT_GT(whole.first, 100u);
  EXPECT_EQ(whole, halves);
}

TEST(CdtTwoHalves, BoundaryAndHoleRings) {
  // The boundary ring crosses the split line; one hole is left of it, one
  // straddles it: the domain is classified after the merge.
  const std::vector<Point3> pts = randomPoints(kSanitized ? 3000 : 10000, 29, 0, 1000);
  auto run = [&](std::size_t splitMin) {
    CdtOptions options;
    options.splitMinPoints = splitMin;
    Cdt cdt(options);
    const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
    const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
    cdt.insertPoints(pts);
    cdt.addBoundary(std::vector<Point3>{{20, 30, 0}, {980, 10, 0}, {960, 990, 0}, {40, 950, 0}},
                    edge);
    cdt.addHole(std::vector<Point3>{{100, 100, 0}, {300, 120, 0}, {200, 300, 0}}, lake);
    cdt.addHole(std::vector<Point3>{{450, 600, 0}, {560, 610, 0}, {500, 700, 0}}, lake);
    cdt.finalize();
    EXPECT_TRUE(isValid(cdt));
    return cdt.toTinData();
  };
  const TinData whole = run(0), halves = run(kSplit);
  EXPECT_EQ(canonical(whole), canonical(halves));
  EXPECT_EQ(whole.constrainedEdges.size(), halves.constrainedEdges.size());
}

TEST(CdtTwoHalves, SameMeshForAnyThreadCount) {
  std::vector<Point3> pts = randomPoints(kSanitized ? 3000 : 20000, 19, 0, 1000);
  for (int j = 0; j < 40; ++j) {
    for (int i = 0; i < 40; ++i) pts.push_back({400.0 + 5 * i, 300.0 + 5 * j, 1});
  }
  std::vector<std::vector<Point3>> lines;
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> d(0, 1000);
  for (int i = 0; i < 80; ++i) lines.push_back({{d(rng), d(rng), 5}, {d(rng), d(rng), 6}});
  const Built one = build(pts, kSplit, 1, 0.0, lines);
  for (const unsigned threads : {2u, 0u}) {
    const Built many = build(pts, kSplit, threads, 0.0, lines);
    EXPECT_EQ(one.tin.vertices, many.tin.vertices) << threads;
    EXPECT_EQ(one.tin.triangles, many.tin.triangles) << threads;
    EXPECT_EQ(one.tin.constrainedEdges, many.tin.constrainedEdges) << threads;
  }
}

}  // namespace
}  // namespace tinsmith
