// Trimming a convex hull's slivers (core/tin/hull_trim.hpp) on a grid whose
// columns curve, as a DEM's do when projected into another CRS.
#include "core/tin/hull_trim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/cdt/cdt.hpp"
#include "core/mesh/validate.hpp"

namespace tinsmith {
namespace {

/// A 40 × 40 grid of 90 m cells at UTM-sized coordinates whose columns bow
/// east by up to 400 m: the west edge is concave, so the hull closes it with
/// long slivers.
TinData curvedGridTin() {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::SpotHeight, "grid");
  std::vector<Point3> points;
  for (int j = 0; j < 40; ++j) {
    const double bow = 400 * std::sin(3.14159265358979 * j / 39.0);
    for (int i = 0; i < 40; ++i) {
      points.push_back({300000 + 90.0 * i + bow, 4900000 + 90.0 * j, 100 + 5.0 * i});
    }
  }
  cdt.insertPoints(points, f);
  cdt.finalize();
  return cdt.toTinData();
}

double longestBoundaryEdge(const TinData& tin) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> directed;
  for (const auto& t : tin.triangles) {
    for (int i = 0; i < 3; ++i) directed.insert({t[i], t[(i + 1) % 3]});
  }
  double longest = 0;
  for (const auto& [a, b] : directed) {
    if (directed.count({b, a})) continue;
    longest = std::max(longest, std::hypot(tin.vertices[a].x - tin.vertices[b].x,
                                           tin.vertices[a].y - tin.vertices[b].y));
  }
  return longest;
}

TEST(HullTrim, RemovesTheSliversAlongACurvedEdgeAndKeepsEveryPoint) {
  TinData tin = curvedGridTin();
  ASSERT_GT(longestBoundaryEdge(tin), 1000) << "the hull has no long edge: the test sees nothing";
  const std::size_t before = tin.triangles.size();
  const std::size_t removed = trimHull(tin, 3 * 90.0);
  EXPECT_GT(removed, 0u);
  EXPECT_EQ(tin.triangles.size(), before - removed);
  EXPECT_LE(longestBoundaryEdge(tin), 3 * 90.0);
  // Still one disk, every point a vertex, the new boundary recorded as a
  // closed ring of constrained edges.
  const ValidationReport report = validate(tin);
  EXPECT_TRUE(report.ok) << report.summary();
  EXPECT_EQ(report.boundaryLoops, 1u);
  std::set<std::uint32_t> used;
  for (const auto& t : tin.triangles) used.insert(t.begin(), t.end());
  EXPECT_EQ(used.size(), tin.vertices.size());
  ASSERT_EQ(tin.features.size(), 2u);
  EXPECT_EQ(tin.features[1].kind, FeatureKind::Boundary);
  EXPECT_EQ(tin.constrainedEdges.size(), report.boundaryEdges);
  // A re-triangulation keeps the trimmed domain.
  Cdt again = Cdt::fromTinData(tin);
  again.finalize();
  EXPECT_EQ(again.toTinData().triangles.size(), tin.triangles.size());
}

TEST(HullTrim, ConvexDataAndShortEdgesAreLeftAsTheyAre) {
  TinData tin = curvedGridTin();
  const TinData original = tin;
  EXPECT_EQ(trimHull(tin, 1e6), 0u);
  EXPECT_EQ(tin.triangles, original.triangles);
  EXPECT_EQ(tin.features.size(), original.features.size());
}

}  // namespace
}  // namespace tinsmith
