// Binary triangulations (core/fit/binary_triangulation.hpp; Hjelle & Dæhlen 2.10, 8.10).
#include <gtest/gtest.h>

#include <set>

#include "core/base/error.hpp"
#include "core/fit/binary_triangulation.hpp"
#include "core/mesh/validate.hpp"
#include "tests/core/fit_test_data.hpp"

namespace tinsmith::fit {
namespace {

using testing::conformingSquareMesh;
using testing::Rng;

/// The extracted mesh as positions + dense-id triangles.
std::pair<std::vector<Point2>, std::vector<Triangle>> extract(const BinaryTriangulation& bt) {
  std::vector<Point2> v;
  for (auto k : bt.activeKeys()) v.push_back(bt.position(k));
  std::vector<Triangle> t;
  for (const auto& tr : bt.triangles()) t.push_back({bt.vertexId(tr.l), bt.vertexId(tr.r), bt.vertexId(tr.a)});
  return {v, t};
}

std::string checkMesh(const BinaryTriangulation& bt) {
  const auto [v, t] = extract(bt);
  TinData tin;
  for (const auto& p : v) tin.vertices.push_back({p.x, p.y, 0.0});
  tin.triangles.assign(t.begin(), t.end());
  ValidationOptions vo;
  vo.checkDelaunay = false;  // binary triangulations need not be Delaunay
  const ValidationReport report = validate(tin, vo);
  if (!report.ok || report.boundaryLoops != 1) return "core validator: " + report.summary();
  return conformingSquareMesh(v, t, bt.origin(), bt.size());
}

void expectClosed(const BinaryTriangulation& bt) {
  for (auto k : bt.activeKeys()) {
    for (auto p : bt.parents(k)) EXPECT_TRUE(bt.isActive(p)) << "parent of " << k;
  }
}

TEST(FitBinaryTriangulation, StartsWithCornersAndCentre) {
  BinaryTriangulation bt({0, 0}, 1.0, 4);
  EXPECT_EQ(bt.activeCount(), 5u);
  EXPECT_EQ(bt.triangles().size(), 4u);
  EXPECT_EQ(checkMesh(bt), "");
  EXPECT_EQ(bt.depth(bt.key(0, 0)), 0);
  EXPECT_EQ(bt.depth(bt.key(8, 8)), 1);
  EXPECT_EQ(bt.depth(bt.key(8, 0)), 2);
  EXPECT_EQ(bt.depth(bt.key(4, 4)), 3);
  EXPECT_EQ(bt.depth(bt.key(4, 0)), 4);
  EXPECT_EQ(bt.depth(bt.key(1, 1)), 7);
  EXPECT_EQ(bt.depth(bt.key(1, 0)), 8);
}

TEST(FitBinaryTriangulation, ParentsAreTheBooksExample) {
  // Fig. 8.13: activating v^2_{3,1} of Ψ2 activates its parents v^1_{1,0} and v^1_{2,1}.
  BinaryTriangulation bt({0, 0}, 1.0, 2);
  const auto parents = bt.parents(bt.key(3, 1));
  const std::set<std::uint64_t> got(parents.begin(), parents.end());
  EXPECT_EQ(got, (std::set<std::uint64_t>{bt.key(2, 0), bt.key(4, 2)}));
  EXPECT_EQ(bt.activate(bt.key(3, 1)), 3u);
  EXPECT_TRUE(bt.isActive(bt.key(2, 0)));
  EXPECT_TRUE(bt.isActive(bt.key(4, 2)));
  EXPECT_EQ(bt.activeCount(), 8u);
  EXPECT_EQ(checkMesh(bt), "");
  // Then v^3_{5,3} of Ψ3 pulls in ancestors of Ψ2 and Ψ1.
  BinaryTriangulation bt3({0, 0}, 1.0, 3);
  bt3.activate(bt3.key(6, 2));  // v^2_{3,1} in Ψ3 numbering
  const std::size_t before = bt3.activeCount();
  EXPECT_GT(bt3.activate(bt3.key(5, 3)), 1u);
  EXPECT_GT(bt3.activeCount(), before + 1);
  expectClosed(bt3);
  EXPECT_EQ(checkMesh(bt3), "");
}

TEST(FitBinaryTriangulation, SplitVertexIndexIsTheMeanOfItsEdgeEnds) {
  BinaryTriangulation bt({0, 0}, 1.0, 6);
  Rng rng(3);
  for (int i = 0; i < 60; ++i) bt.activate(bt.key(rng.next() % 65, rng.next() % 65));
  for (const auto& t : bt.triangles()) {
    if (t.depth > 2 * bt.gridLevels() - 2) continue;  // the finest triangles split no further
    const std::uint64_t j = (t.l + t.r) / 2;
    EXPECT_EQ((t.l + t.r) % 2, 0u);
    EXPECT_EQ(2 * bt.column(j), bt.column(t.l) + bt.column(t.r));
    EXPECT_EQ(2 * bt.row(j), bt.row(t.l) + bt.row(t.r));
  }
  for (auto k : bt.activeKeys()) {
    if (bt.depth(k) < 2) continue;
    const auto ends = bt.splitEdge(k);
    EXPECT_EQ((ends[0] + ends[1]) / 2, k);
    EXPECT_TRUE(bt.isActive(ends[0]) && bt.isActive(ends[1]));
    EXPECT_LT(bt.vertexId(ends[0]), bt.vertexId(k));  // ancestors come first
    EXPECT_LT(bt.vertexId(ends[1]), bt.vertexId(k));
  }
}

TEST(FitBinaryTriangulation, FullGridTriangleAndVertexCounts) {
  // All vertices of depth ≤ d active: 2^(d+1) triangles; Ψk full (d = 2k) has
  // (2^k + 1)² vertices and 2·4^k triangles; with all centres of Ψk cells
  // (d = 2k + 1), (2^k + 1)² + 4^k vertices.
  const int K = 5;
  for (int d = 1; d <= 2 * K; ++d) {
    BinaryTriangulation bt({0, 0}, 2.0, K);
    for (std::uint64_t j = 0; j <= bt.side(); ++j) {
      for (std::uint64_t i = 0; i <= bt.side(); ++i) {
        if (bt.depth(bt.key(i, j)) <= d) bt.activate(bt.key(i, j));
      }
    }
    const auto tris = bt.triangles();
    EXPECT_EQ(tris.size(), std::size_t{1} << (d + 1)) << d;
    const std::uint64_t k = static_cast<std::uint64_t>(d / 2);
    const std::uint64_t gridVerts = ((std::uint64_t{1} << k) + 1) * ((std::uint64_t{1} << k) + 1);
    EXPECT_EQ(bt.activeCount(), d % 2 == 0 ? gridVerts : gridVerts + (std::uint64_t{1} << (2 * k))) << d;
    EXPECT_EQ(checkMesh(bt), "") << d;
  }
  // The book: Ψ7 with the centre of every cell active has 33 025 vertices.
  EXPECT_EQ(129u * 129u + 128u * 128u, 33025u);
}

TEST(FitBinaryTriangulation, RandomActivationsStayClosedAndConforming) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    BinaryTriangulation bt({-3.5, 7.25}, 10.0, 7);
    Rng rng(seed);
    for (int i = 0; i < 40; ++i) {
      const std::size_t before = bt.activeCount();
      const std::size_t added = bt.activate(bt.key(rng.next() % 129, rng.next() % 129));
      EXPECT_EQ(bt.activeCount(), before + added);
    }
    expectClosed(bt);
    EXPECT_EQ(checkMesh(bt), "") << seed;
    // Euler for a triangulated disk: |T| = 2|V| − |Vb| − 2.
    const auto [v, t] = extract(bt);
    std::size_t boundary = 0;
    for (const auto& p : v) {
      boundary += (p.x == -3.5 || p.x == 6.5 || p.y == 7.25 || p.y == 17.25) ? 1 : 0;
    }
    EXPECT_EQ(t.size(), 2 * v.size() - boundary - 2);
  }
}

TEST(FitBinaryTriangulation, LocationFindsTheContainingTriangle) {
  BinaryTriangulation bt({100.0, 200.0}, 50.0, 8);
  Rng rng(5);
  for (int i = 0; i < 200; ++i) bt.activate(bt.key(rng.next() % 257, rng.next() % 257));
  const auto [v, t] = extract(bt);
  for (int i = 0; i < 2000; ++i) {
    const Point2 p{100.0 + 50.0 * rng.uniform(), 200.0 + 50.0 * rng.uniform()};
    const auto loc = bt.locate(p);
    for (double b : loc.barycentric) EXPECT_GE(b, -1e-12);
    const Point2 l = bt.position(loc.triangle.l), r = bt.position(loc.triangle.r), a = bt.position(loc.triangle.a);
    EXPECT_NEAR(loc.barycentric[0] * l.x + loc.barycentric[1] * r.x + loc.barycentric[2] * a.x, p.x, 1e-9);
    EXPECT_NEAR(loc.barycentric[0] * l.y + loc.barycentric[1] * r.y + loc.barycentric[2] * a.y, p.y, 1e-9);
    // The located triangle is a leaf: its split vertex is not active (or does not exist).
    EXPECT_FALSE(loc.triangle.depth <= 2 * bt.gridLevels() - 2 && bt.isActive((loc.triangle.l + loc.triangle.r) / 2));
    const auto again = bt.triangleFromPath(loc.triangle.path);
    EXPECT_EQ(again.l, loc.triangle.l);
    EXPECT_EQ(again.a, loc.triangle.a);
    EXPECT_EQ(again.r, loc.triangle.r);
  }
  // Corners and edges of the domain are inside; beyond is an error.
  EXPECT_NO_THROW((void)bt.locate({100.0, 200.0}));
  EXPECT_NO_THROW((void)bt.locate({150.0, 250.0}));
  EXPECT_THROW((void)bt.locate({99.0, 210.0}), Error);
}

// Regression: a data point on the square's east edge (SRTM N44W072 in UTM
// 19N, the tiler's square from its extent) was "outside the square domain":
// (x − origin)·(side / size) rounded past the side.
TEST(FitBinaryTriangulation, PointsOnTheSquaresEdgeAreInsideDespiteRounding) {
  Rng rng(44);
  int roundedPast = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Point2 origin{2e5 + 3e5 * rng.uniform(), 4e6 + 1e6 * rng.uniform()};
    const double size = 1e3 + 2e5 * rng.uniform();
    const BinaryTriangulation bt(origin, size, 12);
    const Point2 corner{origin.x + size, origin.y + size};
    const double side = static_cast<double>(bt.side());
    const double scale = side / size;
    if ((corner.x - origin.x) * scale > side || (corner.y - origin.y) * scale > side) ++roundedPast;
    const Point2 g = bt.toGrid(corner);
    ASSERT_LE(g.x, side);
    ASSERT_LE(g.y, side);
    EXPECT_NO_THROW((void)bt.locate(corner)) << trial;
  }
  EXPECT_GT(roundedPast, 0) << "no trial rounded past the side: the test would not catch the bug";
  // Beyond rounding, a point is still outside.
  const BinaryTriangulation bt({0.0, 0.0}, 100.0, 8);
  EXPECT_THROW((void)bt.locate({100.001, 50.0}), Error);
}

TEST(FitBinaryTriangulation, NestedLocationMatchesLocationFromTheRoot) {
  BinaryTriangulation bt({0, 0}, 1.0, 8);
  Rng rng(8);
  std::vector<Point2> pts;
  std::vector<std::uint64_t> paths;
  for (int i = 0; i < 500; ++i) {
    pts.push_back({rng.uniform(), rng.uniform()});
    paths.push_back(bt.locate(pts.back()).triangle.path);
  }
  for (int round = 0; round < 5; ++round) {
    for (int i = 0; i < 50; ++i) bt.activate(bt.key(rng.next() % 257, rng.next() % 257));
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const auto nested = bt.locateFrom(pts[i], paths[i]);
      const auto direct = bt.locate(pts[i]);
      EXPECT_EQ(nested.triangle.path, direct.triangle.path);
      paths[i] = nested.triangle.path;
    }
  }
}

TEST(FitBinaryTriangulation, TriangleStripCoversEveryTriangleOnce) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    BinaryTriangulation bt({0, 0}, 1.0, 6);
    Rng rng(seed);
    for (int i = 0; i < 30; ++i) bt.activate(bt.key(rng.next() % 65, rng.next() % 65));
    auto canonical = [](std::uint64_t a, std::uint64_t b, std::uint64_t c) {
      // Rotate so the smallest key is first (keeps orientation).
      if (b < a && b < c) return std::array<std::uint64_t, 3>{b, c, a};
      if (c < a && c < b) return std::array<std::uint64_t, 3>{c, a, b};
      return std::array<std::uint64_t, 3>{a, b, c};
    };
    std::multiset<std::array<std::uint64_t, 3>> expected, got;
    for (const auto& t : bt.triangles()) expected.insert(canonical(t.l, t.r, t.a));
    const auto s = bt.triangleStrip();
    for (std::size_t i = 0; i + 2 < s.size(); ++i) {
      if (s[i] == s[i + 1] || s[i + 1] == s[i + 2] || s[i] == s[i + 2]) continue;
      got.insert(i % 2 == 0 ? canonical(s[i], s[i + 1], s[i + 2]) : canonical(s[i + 1], s[i], s[i + 2]));
    }
    EXPECT_EQ(got, expected) << seed;
    EXPECT_LT(10 * s.size(), 17 * expected.size());  // a strip (about 1.5 vertices a triangle), not a list
  }
}

TEST(FitBinaryTriangulation, KeyIndexMapDoesNotFindTheReservedEmptyKey) {
  // Regression: find(kEmpty) met an empty slot, took it for a match and
  // returned that slot's id (0) instead of kNone.
  KeyIndexMap map;
  EXPECT_EQ(map.find(KeyIndexMap::kEmpty), KeyIndexMap::kNone);
  for (std::uint32_t id = 0; id < 100; ++id) EXPECT_TRUE(map.insert(3 * std::uint64_t{id} + 1, id));
  EXPECT_EQ(map.find(KeyIndexMap::kEmpty), KeyIndexMap::kNone);
  EXPECT_EQ(map.find(1), 0u);
  EXPECT_EQ(map.find(298), 99u);
  EXPECT_EQ(map.find(2), KeyIndexMap::kNone);
  // The reserved key is never stored.
  EXPECT_FALSE(map.insert(KeyIndexMap::kEmpty, 7));
  EXPECT_EQ(map.size(), 100u);
  EXPECT_EQ(map.find(KeyIndexMap::kEmpty), KeyIndexMap::kNone);
}

TEST(FitBinaryTriangulation, MemoryFollowsTheActiveVertices) {
  // The finest grid of level 30 has 2^60 vertices; one deep vertex (depth 59)
  // needs only its ancestors, a number linear in the depth.
  BinaryTriangulation bt({0, 0}, 1.0, 30);
  const std::uint64_t n = bt.side();
  const std::size_t added = bt.activate(bt.key(n / 3 | 1, n / 5 | 1));
  EXPECT_LT(added, 10u * 60u);
  EXPECT_LT(bt.activeCount(), 10u * 60u + 5u);
  EXPECT_EQ(checkMesh(bt), "");
  EXPECT_THROW(BinaryTriangulation({0, 0}, 0.0, 4), Error);
  EXPECT_THROW(BinaryTriangulation({0, 0}, 1.0, 31), Error);
}

}  // namespace
}  // namespace tinsmith::fit
