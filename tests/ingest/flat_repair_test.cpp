// Flat-triangle detection and repair proposals on hand-made TINs; the
// repair through the CDT on real contour-only data is in tin_builder_test.
#include <gtest/gtest.h>

#include "core/mesh/mesh.hpp"
#include "ingest/build/flat_triangles.hpp"

namespace tinsmith::ingest {
namespace {

// A contour at 10 m bending round a square (a U open to the south), and a
// lower vertex to the south: the two triangles inside the bend are flat.
TinData bendTin() {
  TinData tin;
  tin.vertices = {{0, 0, 10}, {0, 10, 10}, {10, 10, 10}, {10, 0, 10}, {5, -10, 0}};
  tin.triangles = {{0, 3, 2}, {0, 2, 1}, {0, 4, 3}};
  tin.features = {{FeatureKind::Contour, "contours, feature 1"}};
  tin.constrainedEdges = {{0, 1, 0}, {1, 2, 0}, {2, 3, 0}};
  return tin;
}

TEST(FlatTriangles, DetectsTrianglesWithAllVerticesOnOneContourLevel) {
  const TinData tin = bendTin();
  EXPECT_EQ(countFlatTriangles(tin), 2u);
  const auto a = analyseFlatTriangles(tin);
  EXPECT_EQ(a.flatTriangles, (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(a.regions, 1u);
  EXPECT_EQ(a.closedRegions, 0u);
}

TEST(FlatTriangles, ProposesTheMedialMidpointWithZAlongTheSteepestPath) {
  const auto a = analyseFlatTriangles(bendTin());
  // Both flat triangles share the diagonal 0–2: one vertex at its midpoint.
  ASSERT_EQ(a.proposals.size(), 1u);
  EXPECT_EQ(a.proposals[0].x, 5.0);
  EXPECT_EQ(a.proposals[0].y, 5.0);
  // d0 = 5 to the contour, d1 = 15 to the 0 m vertex: 10 + (0 − 10)·5/20.
  EXPECT_DOUBLE_EQ(a.proposals[0].z, 7.5);
}

TEST(FlatTriangles, EqualZOffContoursIsNotFlat) {
  TinData tin = bendTin();
  tin.constrainedEdges.clear();  // the same heights as plain spot heights
  EXPECT_EQ(countFlatTriangles(tin), 0u);
  tin = bendTin();
  tin.features[0].kind = FeatureKind::Lake;  // a lake is flat on purpose
  EXPECT_EQ(countFlatTriangles(tin), 0u);
}

TEST(FlatTriangles, ASummitInsideAClosedContourGetsADome) {
  // A closed contour square at 10 m with a triangle fan around it at 0 m.
  TinData tin;
  tin.vertices = {{0, 0, 10}, {10, 0, 10}, {10, 10, 10}, {0, 10, 10},
                  {-10, -10, 0}, {20, -10, 0}, {20, 20, 0}, {-10, 20, 0}};
  tin.triangles = {{0, 1, 2}, {0, 2, 3},                // inside: flat
                   {4, 5, 1}, {4, 1, 0}, {5, 6, 2}, {5, 2, 1},
                   {6, 7, 3}, {6, 3, 2}, {7, 4, 0}, {7, 0, 3}};
  tin.features = {{FeatureKind::Contour, "summit contour"}};
  tin.constrainedEdges = {{0, 1, 0}, {1, 2, 0}, {2, 3, 0}, {0, 3, 0}};
  const auto a = analyseFlatTriangles(tin);
  EXPECT_EQ(a.flatTriangles.size(), 2u);
  EXPECT_EQ(a.closedRegions, 1u);
  ASSERT_EQ(a.proposals.size(), 1u);
  EXPECT_EQ(a.proposals[0].x, 5.0);
  // Above the contour (the land outside is lower) by half the 10 m interval.
  EXPECT_DOUBLE_EQ(a.proposals[0].z, 15.0);
}

TEST(FlatTriangles, ProposalsTooCloseToAVertexAreSkipped) {
  EXPECT_TRUE(analyseFlatTriangles(bendTin(), 100.0).proposals.empty());
}

// The builder analyses the CDT's Mesh; tests and tools analyse TinData: the
// two give the same result.
TEST(FlatTriangles, MeshAndTinDataGiveTheSameAnalysis) {
  const Mesh mesh = Mesh::fromTinData(bendTin());
  const TinData again = mesh.toTinData();
  EXPECT_EQ(countFlatTriangles(mesh), 2u);
  EXPECT_EQ(countFlatTriangles(again), 2u);
  EXPECT_EQ(contourVertices(mesh), contourVertices(again));
  const auto a = analyseFlatTriangles(mesh), b = analyseFlatTriangles(again);
  EXPECT_EQ(a.flatTriangles, b.flatTriangles);
  EXPECT_EQ(a.regions, b.regions);
  EXPECT_EQ(a.closedRegions, b.closedRegions);
  ASSERT_EQ(a.proposals.size(), 1u);
  ASSERT_EQ(b.proposals.size(), 1u);
  EXPECT_EQ(a.proposals[0], b.proposals[0]);
}

}  // namespace
}  // namespace tinsmith::ingest
