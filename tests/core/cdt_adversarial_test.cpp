// Adversarial inputs for the CDT; every result must pass the validator.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;
using testing::kSanitized;
using testing::randomPoints;

TEST(CdtAdversarial, RegularGridAllCocircular) {
  const int n = kSanitized ? 120 : 1000;
  std::vector<Point3> pts;
  pts.reserve(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) pts.push_back({double(i), double(j), double(i + j)});
  }
  Cdt cdt;
  cdt.insertPoints(pts);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), pts.size());
  EXPECT_EQ(cdt.mesh().triangleCount(), 2u * (n - 1) * (n - 1));
}

TEST(CdtAdversarial, PointsOnACircle) {
  std::vector<Point3> pts;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    pts.push_back({1000 * std::cos(a), 1000 * std::sin(a), 0});
  }
  pts.push_back({0, 0, 5});
  Cdt cdt;
  cdt.insertPoints(pts);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), pts.size());
}

TEST(CdtAdversarial, ExactlyCocircularIntegerCircle) {
  // Pythagorean points on the circle of radius 5·13·17 = 1105 (many exact ones).
  std::vector<Point3> pts;
  const long r2 = 1105L * 1105L;
  for (long x = -1105; x <= 1105; ++x) {
    const long y2 = r2 - x * x;
    const long y = std::lround(std::sqrt(double(y2)));
    if (y * y == y2) {
      pts.push_back({double(x), double(y), 0});
      if (y != 0) pts.push_back({double(x), double(-y), 0});
    }
  }
  ASSERT_GT(pts.size(), 20u);
  Cdt cdt;
  cdt.insertPoints(pts);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
}

TEST(CdtAdversarial, CollinearRunPlusOnePointOff) {
  std::vector<Point3> pts;
  for (int i = 0; i < 5000; ++i) pts.push_back({i * 0.5, i * 0.25, 0});
  pts.push_back({100, 200, 1});
  Cdt cdt;
  cdt.insertPoints(pts);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), pts.size());
  EXPECT_EQ(cdt.mesh().triangleCount(), pts.size() - 2);
}

TEST(CdtAdversarial, HeavyDuplicatesMergeAndAreReported) {
  std::vector<Point3> pts;
  for (int k = 0; k < 50; ++k) {
    for (int i = 0; i < 10; ++i) {
      for (int j = 0; j < 10; ++j) pts.push_back({double(i), double(j), double(k)});
    }
  }
  Cdt cdt;
  cdt.insertPoints(pts);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), 100u);
  EXPECT_EQ(cdt.report().merges.size(), pts.size() - 100);
  // Equal priority: the earliest input's z is kept.
  for (std::uint32_t v = 0; v < 100; ++v) {
    EXPECT_EQ(cdt.mesh().z(cdt.meshVertex(VertexId(v))), 0.0);
  }
}

TEST(CdtAdversarial, SnapToleranceMergesNearDuplicatesByPriority) {
  CdtOptions options;
  options.snapTolerance = 0.01;
  Cdt cdt(options);
  const FeatureId spot = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
  cdt.insertPoints(randomPoints(200, 7), spot);
  const VertexId a = cdt.insertPoint({500, 500, 1}, spot);
  const VertexId b = cdt.insertPoint({500.004, 500.003, 2}, river);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.meshVertex(a), cdt.meshVertex(b));
  EXPECT_EQ(cdt.mesh().z(cdt.meshVertex(a)), 2.0);  // river wins
  bool found = false;
  for (const auto& m : cdt.report().merges) found |= m.keptZ == 2.0 && m.droppedZ == 1.0;
  EXPECT_TRUE(found);
}

TEST(CdtAdversarial, ClusteredPoints) {
  std::vector<Point3> pts;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> d(0, 1);
  for (int c = 0; c < 20; ++c) {
    const double cx = c * 1000.0, cy = (c % 3) * 500.0;
    const double s = std::pow(10.0, -(c % 7));
    for (int i = 0; i < 500; ++i) pts.push_back({cx + s * d(rng), cy + s * d(rng), 0});
  }
  Cdt cdt;
  cdt.insertPoints(pts);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
}

TEST(CdtAdversarial, HugeMagnitudes) {
  for (double scale : {7e6, 1e15, 1e50}) {
    std::vector<Point3> pts;
    for (const Point3& p : randomPoints(2000, 11, 0, 1)) {
      pts.push_back({scale + p.x * scale * 1e-9, scale + p.y * scale * 1e-9, 0});
    }
    for (int i = 0; i < 50; ++i) pts.push_back({scale + i * scale * 1e-11, scale, 0});
    Cdt cdt;
    cdt.insertPoints(pts);
    cdt.finalize();
    EXPECT_TRUE(isValid(cdt)) << "scale " << scale;
  }
}

TEST(CdtAdversarial, ConstraintsCrossingAtOnePoint) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Other, "star");
  cdt.insertPoints(randomPoints(300, 5, -100, 100));
  const int n = 40;
  for (int i = 0; i < n; ++i) {
    const double a = std::numbers::pi * i / n;
    const std::vector<Point3> line{{150 * std::cos(a), 150 * std::sin(a), 0},
                                   {-150 * std::cos(a), -150 * std::sin(a), 0}};
    cdt.insertConstraint(line, f);
  }
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_GT(cdt.report().intersections.size(), 0u);
}

TEST(CdtAdversarial, OverlappingCollinearConstraintsShareEdges) {
  Cdt cdt;
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
  cdt.insertPoints(randomPoints(200, 9));
  const std::vector<Point3> a{{100, 100, 0}, {700, 400, 0}};
  const std::vector<Point3> b{{300, 200, 0}, {900, 500, 0}};
  cdt.insertConstraint(a, road);
  cdt.insertConstraint(b, river);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  // The shared stretch 300,200 – 700,400 carries both features.
  std::size_t both = 0;
  const Mesh& m = cdt.mesh();
  for (std::uint32_t h = 0; h < m.halfedgeCount(); ++h) both += m.edgeFeatures(HalfedgeId(h)).size() == 2;
  EXPECT_GT(both, 0u);
}

TEST(CdtAdversarial, NearlyParallelConstraintsCrossAtTinyAngles) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Contour, "c");
  const FeatureId g = cdt.addFeature(FeatureKind::Road, "r");
  cdt.insertPoints(randomPoints(500, 13));
  for (int i = 0; i < 30; ++i) {
    const double e = std::ldexp(1.0, -10 - i);
    const std::vector<Point3> l1{{0, 500, 0}, {1000, 500 + e, 0}};
    const std::vector<Point3> l2{{0, 500 + e, 10}, {1000, 500 - e, 10}};
    cdt.insertConstraint(l1, f);
    cdt.insertConstraint(l2, g);
  }
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
}

TEST(CdtAdversarial, TJunctions) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Other, "t");
  cdt.insertPoints(randomPoints(100, 17));
  const std::vector<Point3> bar{{100, 500, 0}, {900, 500, 0}};
  cdt.insertConstraint(bar, f);
  for (int i = 1; i < 8; ++i) {
    const std::vector<Point3> stem{{100.0 + i * 100, 500, 0}, {100.0 + i * 100, 100, 0}};
    cdt.insertConstraint(stem, f);
  }
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
}

TEST(CdtAdversarial, ConstraintThroughManyVertices) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Other, "diag");
  std::vector<Point3> pts;
  for (int j = 0; j < 60; ++j) {
    for (int i = 0; i < 60; ++i) pts.push_back({double(i), double(j), 0});
  }
  cdt.insertPoints(pts);
  const std::vector<Point3> diag{{0, 0, 0}, {59, 59, 0}};
  const std::vector<Point3> knight{{0, 0, 0}, {58, 29, 0}};
  cdt.insertConstraint(diag, f);
  cdt.insertConstraint(knight, f);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), pts.size());
}

TEST(CdtAdversarial, SelfCrossingPolyline) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Contour, "zigzag");
  cdt.insertPoints(randomPoints(100, 19));
  std::vector<Point3> zig;
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> d(0, 1000);
  for (int i = 0; i < 60; ++i) zig.push_back({d(rng), d(rng), double(i)});
  cdt.insertConstraint(zig, f, true);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_GT(cdt.report().intersections.size(), 10u);
}

TEST(CdtAdversarial, PolygonWithHoles) {
  Cdt cdt;
  const FeatureId outer = cdt.addFeature(FeatureKind::Boundary, "outer");
  const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
  std::vector<Point3> pts = randomPoints(2000, 29);
  cdt.insertPoints(pts);
  std::vector<Point3> ring;
  for (int i = 0; i < 64; ++i) {
    const double a = 2 * std::numbers::pi * i / 64;
    const double r = 400 + 60 * std::sin(5 * a);
    ring.push_back({500 + r * std::cos(a), 500 + r * std::sin(a), 0});
  }
  cdt.addBoundary(ring, outer);
  const std::vector<Point3> hole{{450, 450, 0}, {450, 550, 0}, {550, 550, 0}, {550, 450, 0}};
  cdt.addHole(hole, lake);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  const ValidationReport r = validate(cdt.mesh());
  EXPECT_EQ(r.boundaryLoops, 2u);
  // No triangle centroid inside the hole or far outside the ring.
  const Mesh& m = cdt.mesh();
  for (std::uint32_t t = 0; t < m.triangleCount(); ++t) {
    const auto v = m.vertices(TriangleId(t));
    const double cx = (m.xy(v[0]).x + m.xy(v[1]).x + m.xy(v[2]).x) / 3;
    const double cy = (m.xy(v[0]).y + m.xy(v[1]).y + m.xy(v[2]).y) / 3;
    EXPECT_FALSE(cx > 450 && cx < 550 && cy > 450 && cy < 550);
    EXPECT_LT(std::hypot(cx - 500, cy - 500), 461);
  }
  EXPECT_GT(cdt.report().dropped.size(), 0u);  // points outside the ring
}

TEST(CdtAdversarial, BadInputThrowsError) {
  {
    Cdt cdt;
    EXPECT_THROW(cdt.insertPoint({NAN, 0, 0}), Error);
    EXPECT_THROW(cdt.insertPoint({0, INFINITY, 0}), Error);
    try {
      cdt.insertPoint({0, 0, NAN});
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
    }
  }
  {
    Cdt cdt;
    cdt.insertPoints(std::vector<Point3>{{0, 0, 0}, {1, 1, 0}, {2, 2, 0}, {1, 1, 5}});
    try {
      cdt.finalize();
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Geometry);
    }
  }
  {
    // Outside the range where exact predicates on doubles cannot underflow/overflow.
    Cdt cdt;
    EXPECT_THROW(cdt.insertPoint({1e100, 0, 0}), Error);
    EXPECT_THROW(cdt.insertPoint({1, 4.9e-324, 0}), Error);
    EXPECT_NO_THROW(cdt.insertPoint({0, 1e-40, 0}));
  }
  {
    Cdt cdt;
    EXPECT_THROW(cdt.finalize(), Error);
    cdt.insertPoint({1, 1, 1});
    cdt.insertPoint({1, 1, 1});
    EXPECT_THROW(cdt.finalize(), Error);
  }
}

TEST(CdtAdversarial, ZeroLengthSegmentsAreDroppedAndReported) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Road, "r");
  cdt.insertPoints(randomPoints(50, 31));
  const std::vector<Point3> line{{10, 10, 0}, {10, 10, 0}, {20, 30, 0}};
  cdt.insertConstraint(line, f);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  ASSERT_EQ(cdt.report().dropped.size(), 1u);
  EXPECT_EQ(cdt.report().dropped[0].what, CdtReport::Dropped::What::ZeroLengthSegment);
}

TEST(CdtAdversarial, CrossingZFromHigherPriorityFeature) {
  Cdt cdt;
  const FeatureId contour = cdt.addFeature(FeatureKind::Contour, "c");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "r");
  cdt.insertPoints(std::vector<Point3>{{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}});
  cdt.insertConstraint(std::vector<Point3>{{1, 5, 100}, {9, 5, 100}}, contour);
  cdt.insertConstraint(std::vector<Point3>{{5, 1, 1}, {5, 9, 3}}, river);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  ASSERT_EQ(cdt.report().intersections.size(), 1u);
  const auto& ev = cdt.report().intersections[0];
  EXPECT_DOUBLE_EQ(ev.at.z, 2.0);
  EXPECT_DOUBLE_EQ(ev.zExisting, 100.0);
  EXPECT_EQ(ev.existing, contour);
  EXPECT_EQ(ev.inserted, river);
}

TEST(CdtAdversarial, TwoHolesTouchingAtAVertex) {
  // The holes share their leftmost vertex: the domain's boundary passes it
  // twice in one loop (found by the fuzzer; the validator took that loop's
  // turn at the shared vertex for its orientation). Four mirror images, so
  // that the loop reaches the shared vertex first from either hole.
  for (const double sx : {1.0, -1.0}) {
    for (const double sy : {1.0, -1.0}) {
      auto at = [&](double x, double y) { return Point3{5 + sx * (x - 5), 5 + sy * (y - 5), 0}; };
      Cdt cdt;
      const FeatureId outer = cdt.addFeature(FeatureKind::Boundary, "outer");
      const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
      cdt.insertPoints(randomPoints(500, 31, 0, 10));
      cdt.addBoundary(std::vector<Point3>{at(0, 0), at(10, 0), at(10, 10), at(0, 10)}, outer);
      cdt.addHole(std::vector<Point3>{at(2, 2), at(4, 1), at(4, 3)}, lake);
      cdt.addHole(std::vector<Point3>{at(2, 2), at(4, 5), at(3, 6)}, lake);
      cdt.finalize();
      EXPECT_TRUE(isValid(cdt)) << sx << " " << sy;
      const ValidationReport r = validate(cdt.mesh());
      EXPECT_EQ(r.boundaryLoops, 2u);  // the outer ring; both holes in one loop
    }
  }
}

TEST(CdtAdversarial, DeterministicOutput) {
  auto build = [] {
    Cdt cdt;
    const FeatureId f = cdt.addFeature(FeatureKind::Other, "x");
    std::vector<Point3> pts;
    for (int j = 0; j < 30; ++j) {
      for (int i = 0; i < 30; ++i) pts.push_back({double(i), double(j), 0});
    }
    cdt.insertPoints(pts);
    cdt.insertConstraint(std::vector<Point3>{{0.5, 0.5, 0}, {28.5, 20.25, 0}}, f);
    cdt.finalize();
    return cdt.toTinData();
  };
  const TinData a = build(), b = build();
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.constrainedEdges, b.constrainedEdges);
}

TEST(CdtAdversarial, IncrementalInsertAfterFinalize) {
  Cdt cdt;
  const FeatureId f = cdt.addFeature(FeatureKind::Road, "r");
  cdt.insertPoints(randomPoints(500, 37));
  cdt.insertConstraint(std::vector<Point3>{{10, 10, 0}, {990, 990, 0}}, f);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  cdt.insertPoints(randomPoints(500, 41, -200, 1200));
  cdt.insertConstraint(std::vector<Point3>{{10, 990, 0}, {990, 10, 0}}, f);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.report().intersections.size(), 1u);
}

TEST(CdtAdversarial, FromTinDataRoundTrip) {
  Cdt cdt;
  const FeatureId outer = cdt.addFeature(FeatureKind::Boundary, "outer");
  const FeatureId hole = cdt.addFeature(FeatureKind::Hole, "hole");
  cdt.insertPoints(randomPoints(400, 43));
  cdt.addBoundary(std::vector<Point3>{{100, 100, 0}, {900, 100, 0}, {500, 500, 0}, {900, 900, 0},
                                      {100, 900, 0}},
                  outer);
  cdt.addHole(std::vector<Point3>{{200, 600, 0}, {300, 600, 0}, {300, 700, 0}}, hole);
  cdt.finalize();
  ASSERT_TRUE(isValid(cdt));
  const TinData tin = cdt.toTinData();
  EXPECT_TRUE(validate(tin).ok) << validate(tin).summary();
  Cdt again = Cdt::fromTinData(tin);
  again.finalize();
  EXPECT_TRUE(isValid(again));
  const TinData tin2 = again.toTinData();
  EXPECT_EQ(tin2.vertices.size(), tin.vertices.size());
  EXPECT_EQ(tin2.triangles.size(), tin.triangles.size());
  EXPECT_EQ(tin2.constrainedEdges.size(), tin.constrainedEdges.size());
}

}  // namespace
}  // namespace tinsmith

namespace tinsmith {
namespace {

// Found by the fuzzer: points inserted (in a second finalize) into triangles
// with constrained edges left stale constraint flags on the split triangle's
// new inner edges, so the LOP skipped them.
TEST(CdtRegression, PointInsertedIntoTriangleWithConstrainedEdges) {
  Cdt cdt;
  const FeatureId b = cdt.addFeature(FeatureKind::Boundary, "b");
  const FeatureId f = cdt.addFeature(FeatureKind::Other, "o");
  cdt.addBoundary(std::vector<Point3>{{-15000.000000000002, -20000, 17},
                                      {16000.000000000002, 16000, 53},
                                      {-11000.000000000002, -11000, 53}},
                  b);
  cdt.finalize();
  EXPECT_TRUE(testing::isValid(cdt));
  cdt.insertConstraint(std::vector<Point3>{{-11000, -11000, 0},
                                           {-11999.999999999998, -14000, 26},
                                           {17000, -20000, 0},
                                           {-20000, -20000, 0}},
                       f);
  cdt.finalize();
  EXPECT_TRUE(testing::isValid(cdt));
}

// Found by the fuzzer: the validator took a 1-ulp sliver's boundary loop for
// clockwise (float area) — loop orientation is now decided exactly.
TEST(CdtRegression, SliverTriangleAtUtmCoordinatesIsValid) {
  TinData tin;
  const double y = std::nextafter(7000500.0, INFINITY);
  tin.vertices = {{7000000, 7000000, 0}, {7001000, 7001000, 0}, {7000500, y, 0}};
  tin.triangles = {{0, 1, 2}};
  const ValidationReport r = validate(tin);
  EXPECT_TRUE(r.ok) << r.summary();
}

}  // namespace
}  // namespace tinsmith
