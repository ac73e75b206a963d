// The half-edge mesh and the validator: the validator must accept good meshes
// and name what is wrong with broken ones.
#include "core/mesh/mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "core/mesh/validate.hpp"

namespace tinsmith {
namespace {

// A unit square split along the diagonal 0-2, plus a constrained diagonal.
TinData square() {
  TinData tin;
  tin.vertices = {{0, 0, 0}, {1, 0, 1}, {1, 1, 2}, {0, 1, 3}};
  tin.triangles = {{0, 1, 2}, {0, 2, 3}};
  tin.features = {{FeatureKind::Road, "road"}};
  tin.constrainedEdges = {{0, 2, 0}};
  return tin;
}

bool mentions(const ValidationReport& r, const std::string& word) {
  for (const auto& p : r.problems) {
    if (p.find(word) != std::string::npos) return true;
  }
  return false;
}

TEST(Mesh, StrongIdsHaveAnInvalidDefault) {
  VertexId v;
  EXPECT_FALSE(v.valid());
  EXPECT_TRUE(VertexId(0).valid());
  EXPECT_EQ(HalfedgeId::invalid().value, HalfedgeId::kInvalid);
  static_assert(!std::is_convertible_v<VertexId, TriangleId>);
}

TEST(Mesh, TopologyOfASquare) {
  const Mesh m = Mesh::fromTinData(square());
  EXPECT_EQ(m.vertexCount(), 4u);
  EXPECT_EQ(m.triangleCount(), 2u);
  EXPECT_EQ(m.boundaryHalfedges().size(), 4u);
  const HalfedgeId diag = Mesh::halfedge(TriangleId(0), 2);  // 2→0
  EXPECT_EQ(m.origin(diag), VertexId(2));
  EXPECT_EQ(m.target(diag), VertexId(0));
  ASSERT_TRUE(m.twin(diag).valid());
  EXPECT_EQ(m.twin(m.twin(diag)), diag);
  EXPECT_TRUE(m.isConstrained(diag));
  EXPECT_TRUE(m.isConstrained(m.twin(diag)));
  ASSERT_EQ(m.edgeFeatures(diag).size(), 1u);
  std::size_t star = 0;
  m.forEachOutgoing(VertexId(0), [&](HalfedgeId h) {
    EXPECT_EQ(m.origin(h), VertexId(0));
    ++star;
  });
  EXPECT_EQ(star, 2u);
  const ValidationReport r = validate(m);
  EXPECT_TRUE(r.ok) << r.summary();
  EXPECT_EQ(r.edges, 5u);
  EXPECT_EQ(r.boundaryLoops, 1u);
  EXPECT_EQ(r.constrainedEdges, 1u);
}

TEST(Mesh, TinDataRoundTrip) {
  const TinData tin = square();
  const TinData back = Mesh::fromTinData(tin).toTinData();
  EXPECT_EQ(back.vertices, tin.vertices);
  EXPECT_EQ(back.triangles, tin.triangles);
  EXPECT_EQ(back.constrainedEdges, tin.constrainedEdges);
}

TEST(Validator, FindsClockwiseTriangle) {
  TinData tin = square();
  tin.triangles[1] = {0, 3, 2};
  const ValidationReport r = validate(tin);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(mentions(r, "counter-clockwise")) << r.summary();
}

TEST(Validator, FindsNonDelaunayEdge) {
  TinData tin;
  // A thin quad whose diagonal 0-2 is the long one: not Delaunay.
  tin.vertices = {{0, 0, 0}, {5, -1, 0}, {10, 0, 0}, {5, 1, 0}};
  tin.triangles = {{0, 1, 2}, {0, 2, 3}};
  ValidationReport r = validate(tin);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(mentions(r, "Delaunay")) << r.summary();
  // Constrained, the same edge is fine.
  tin.features = {{FeatureKind::Other, "x"}};
  tin.constrainedEdges = {{0, 2, 0}};
  r = validate(tin);
  EXPECT_TRUE(r.ok) << r.summary();
}

TEST(Validator, FindsBadIndicesAndNonManifoldEdges) {
  TinData tin = square();
  tin.triangles.push_back({0, 1, 9});
  tin.triangles.push_back({0, 1, 3});
  const ValidationReport r = validate(tin);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(mentions(r, "out of range")) << r.summary();
}

TEST(Validator, FindsConstraintThatIsNotAnEdge) {
  TinData tin = square();
  tin.constrainedEdges.push_back({1, 3, 0});
  tin.constrainedEdges.push_back({0, 1, 7});
  const ValidationReport r = validate(tin);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(mentions(r, "not an edge")) << r.summary();
  EXPECT_TRUE(mentions(r, "unknown feature")) << r.summary();
}

TEST(Validator, FindsFoldedStar) {
  // A centre vertex whose fan wraps twice would need crossing triangles; a
  // simpler fold: two triangles on the same side of their shared edge.
  TinData tin;
  tin.vertices = {{0, 0, 0}, {4, 0, 0}, {2, 3, 0}, {2, 1, 0}};
  tin.triangles = {{0, 1, 2}, {1, 0, 3}};  // (1,0,3) is clockwise
  const ValidationReport r = validate(tin);
  EXPECT_FALSE(r.ok);
}

TEST(Validator, FindsAStarThatWindsTwice) {
  // Five CCW triangles around a centre whose rim steps 144° at a time: every
  // triangle is fine and every spoke has its twin, but the star goes twice
  // around the centre (a double cover, which no plane TIN can be).
  TinData tin;
  tin.vertices = {{0, 0, 0}};
  for (int i = 0; i < 5; ++i) {
    const double a = i * 144.0 * 3.14159265358979323846 / 180.0;
    tin.vertices.push_back({std::cos(a), std::sin(a), 0});
  }
  for (std::uint32_t i = 0; i < 5; ++i) tin.triangles.push_back({0, 1 + i, 1 + (i + 1) % 5});
  const ValidationReport r = validate(tin);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(mentions(r, "winds 2 times around it")) << r.summary();
}

TEST(Validator, FindsTwinsThatAreNotEachOthers) {
  // Twins are checked once per pair, from the lower half-edge; a twin link
  // that is not returned must still be found, from either side.
  for (const bool lowerSide : {true, false}) {
    MeshStorage storage = Mesh::fromTinData(square()).release();
    // The diagonal: half-edge 2 (2→0) and its twin 3 (0→2). Point one of them
    // at a boundary half-edge of the other triangle instead.
    ASSERT_EQ(storage.twins[2], 3u);
    if (lowerSide)
      storage.twins[2] = 4;
    else
      storage.twins[3] = 1;
    const ValidationReport r = validate(Mesh::adopt(std::move(storage)));
    EXPECT_FALSE(r.ok);
    EXPECT_TRUE(mentions(r, "not symmetric")) << r.summary();
  }
}

TEST(Validator, FindsAnEdgeConstrainedOnOneSideOnly) {
  // The diagonal's two half-edges (2 and 3) both carry the road; take it off
  // one of them, either one.
  for (const std::uint32_t side : {2u, 3u}) {
    MeshStorage storage = Mesh::fromTinData(square()).release();
    ASSERT_EQ(storage.consBits.at(0), (std::uint64_t{1} << 2) | (std::uint64_t{1} << 3));
    storage.consBits[0] &= ~(std::uint64_t{1} << side);
    storage.featureBegin = {0, 1};
    storage.featureIds = {0};
    const ValidationReport r = validate(Mesh::adopt(std::move(storage)));
    EXPECT_FALSE(r.ok);
    EXPECT_TRUE(mentions(r, "different constraint features on its sides")) << side << ": " << r.summary();
    EXPECT_EQ(r.constrainedEdges, 1u) << side;
  }
}

// A grid of n × n squares, two triangles each.
TinData grid(std::uint32_t n) {
  TinData tin;
  for (std::uint32_t j = 0; j <= n; ++j)
    for (std::uint32_t i = 0; i <= n; ++i) tin.vertices.push_back({double(i), double(j), 0});
  for (std::uint32_t j = 0; j < n; ++j) {
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      tin.triangles.push_back({a, b, c});
      tin.triangles.push_back({a, c, d});
    }
  }
  return tin;
}

TEST(Validator, TheReportIsTheSameForAnyThreadCount) {
  // Large enough for the passes to run in parts; broken in many places, so
  // that which problems are listed depends on the order they are merged in.
  TinData tin = grid(200);
  for (std::size_t t = 7; t < tin.triangles.size(); t += 997) std::swap(tin.triangles[t][1], tin.triangles[t][2]);
  tin.vertices[5000].x = std::nan("");
  const Mesh m = Mesh::fromTinData(tin);
  const ValidationReport one = validate(m, {.threads = 1});
  EXPECT_FALSE(one.ok);
  EXPECT_GT(one.problemCount, one.problems.size());
  for (unsigned threads : {2u, 3u, 8u}) {
    const ValidationReport r = validate(m, {.threads = threads});
    EXPECT_EQ(r.problemCount, one.problemCount) << threads;
    EXPECT_EQ(r.problems, one.problems) << threads;
    EXPECT_EQ(r.summary(), one.summary()) << threads;
  }
  const ValidationReport good = validate(grid(200), {.threads = 2});
  EXPECT_TRUE(good.ok) << good.summary();
  EXPECT_EQ(good.vertices, 201u * 201u);
}

TEST(Validator, AcceptsPolygonWithHoleAndCountsLoops) {
  // A 3x3 grid of squares without the middle one.
  TinData tin;
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) tin.vertices.push_back({double(i), double(j), 0});
  }
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      if (i == 1 && j == 1) continue;
      const std::uint32_t a = j * 4 + i, b = a + 1, c = a + 5, d = a + 4;
      tin.triangles.push_back({a, b, c});
      tin.triangles.push_back({a, c, d});
    }
  }
  const ValidationReport r = validate(tin);
  EXPECT_TRUE(r.ok) << r.summary();
  EXPECT_EQ(r.boundaryLoops, 2u);
}

}  // namespace
}  // namespace tinsmith
