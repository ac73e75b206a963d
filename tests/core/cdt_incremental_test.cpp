// The output mesh takes over the working triangle arrays (Cdt::mesh()); more
// input after that must give exactly the result of never having built it.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;

std::vector<Point3> scatter(int n, std::uint64_t seed, double lo, double hi) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(lo, hi);
  std::vector<Point3> pts;
  for (int i = 0; i < n; ++i) pts.push_back({d(rng), d(rng), d(rng)});
  // Exact duplicates: merged vertices have no mesh vertex of their own.
  for (int i = 0; i < n / 10; ++i) pts.push_back(pts[static_cast<std::size_t>(i) * 3]);
  return pts;
}

/// Builds in three rounds; `peek` calls mesh() (and validates) between rounds.
TinData build(bool peek, bool domain) {
  Cdt cdt;
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
  const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
  cdt.insertPoints(scatter(600, 5, 0, 1000));
  if (domain) {
    cdt.addBoundary(std::vector<Point3>{{50, 50, 0}, {950, 80, 0}, {900, 950, 0}, {80, 900, 0}},
                    edge);
    cdt.addHole(std::vector<Point3>{{400, 400, 0}, {600, 420, 0}, {500, 600, 0}}, lake);
  }
  cdt.insertConstraint(std::vector<Point3>{{10, 10, 0}, {990, 990, 0}}, road);
  cdt.finalize();
  if (peek) {
    EXPECT_TRUE(isValid(cdt));
    EXPECT_GT(cdt.mesh().triangleCount(), 0u);
    cdt.finalize();  // nothing new: the mesh stands
    EXPECT_TRUE(isValid(cdt));
  }
  cdt.insertPoints(scatter(400, 9, -100, 1100));
  cdt.insertConstraint(std::vector<Point3>{{10, 990, 0}, {990, 10, 0}, {500, 30, 0}}, road);
  cdt.finalize();
  if (peek) {
    EXPECT_TRUE(isValid(cdt));
  }
  cdt.insertPoints(scatter(300, 13, 100, 900));
  cdt.insertConstraint(std::vector<Point3>{{100, 500, 0}, {900, 500, 0}}, road);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  return cdt.toTinData();
}

TEST(CdtIncremental, MeshBetweenFinalizesChangesNothing) {
  for (const bool domain : {false, true}) {
    const TinData a = build(false, domain), b = build(true, domain);
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.constrainedEdges, b.constrainedEdges);
    EXPECT_GT(a.triangles.size(), 1000u);
  }
}

TEST(CdtIncremental, OutputMeshMatchesMeshBuiltFromItsTinData) {
  Cdt cdt;
  const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  cdt.insertPoints(scatter(2000, 31, 0, 1000));
  cdt.addHole(std::vector<Point3>{{400, 400, 0}, {600, 420, 0}, {500, 600, 0}}, lake);
  cdt.insertConstraint(std::vector<Point3>{{10, 10, 0}, {990, 990, 0}}, road);
  cdt.finalize();
  const Mesh& a = cdt.mesh();
  const Mesh b = Mesh::fromTinData(cdt.toTinData());
  ASSERT_EQ(a.halfedgeCount(), b.halfedgeCount());
  ASSERT_EQ(a.vertexCount(), b.vertexCount());
  std::size_t constrained = 0;
  for (std::uint32_t h = 0; h < a.halfedgeCount(); ++h) {
    EXPECT_EQ(a.twin(HalfedgeId(h)), b.twin(HalfedgeId(h)));
    EXPECT_EQ(a.isConstrained(HalfedgeId(h)), b.isConstrained(HalfedgeId(h)));
    const auto fa = a.edgeFeatures(HalfedgeId(h)), fb = b.edgeFeatures(HalfedgeId(h));
    EXPECT_TRUE(std::equal(fa.begin(), fa.end(), fb.begin(), fb.end()));
    constrained += a.isConstrained(HalfedgeId(h));
  }
  EXPECT_GE(constrained, 5u);
  for (std::uint32_t v = 0; v < a.vertexCount(); ++v) {
    EXPECT_EQ(a.outgoing(VertexId(v)), b.outgoing(VertexId(v))) << v;
  }
}

TEST(CdtThreads, SameResultForAnyThreadCount) {
  const int n = testing::kSanitized ? 6000 : 40000;
  auto run = [&](unsigned threads) {
    CdtOptions options;
    options.threads = threads;
    Cdt cdt(options);
    const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
    cdt.insertPoints(scatter(n, 21, 0, 1000));
    // A lattice too: exact cocircular ties must be decided the same way.
    std::vector<Point3> grid;
    for (int j = 0; j < 60; ++j) {
      for (int i = 0; i < 60; ++i) grid.push_back({200.0 + 5 * i, 300.0 + 5 * j, 1});
    }
    cdt.insertPoints(grid);
    cdt.insertConstraint(std::vector<Point3>{{10, 10, 0}, {990, 990, 0}, {990, 20, 0}}, road);
    cdt.finalize();
    cdt.insertPoints(scatter(n / 2, 22, -50, 1050));
    cdt.finalize();
    return cdt.toTinData();
  };
  const TinData a = run(1);
  for (const unsigned threads : {2u, 3u, 0u}) {
    const TinData b = run(threads);
    EXPECT_EQ(a.vertices, b.vertices) << threads;
    EXPECT_EQ(a.triangles, b.triangles) << threads;
    EXPECT_EQ(a.constrainedEdges, b.constrainedEdges) << threads;
  }
}

}  // namespace
}  // namespace tinsmith
