// Regressions found by a review of core/cdt/cdt.cpp: input added after
// finalize(), the nesting of constraint reroutes, the validator's chain
// search, concurrent readers of a finalized Cdt, holes outside every boundary
// and polylines with a bad vertex.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <latch>
#include <thread>
#include <vector>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/cdt/cdt_test_access.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;
using testing::randomPoints;
namespace sliver = testing::crossing_beside_a_sliver;

double area(const Mesh& mesh) {
  double sum = 0;
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
    const auto v = mesh.vertices(TriangleId(t));
    const Point2 a = mesh.xy(v[0]), b = mesh.xy(v[1]), c = mesh.xy(v[2]);
    sum += 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
  }
  return sum;
}

std::vector<Point3> square(double lo, double hi) {
  return {{lo, lo, 0}, {hi, lo, 0}, {hi, hi, 0}, {lo, hi, 0}};
}

ErrorKind kindOf(const auto& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.kind();
  }
  ADD_FAILURE() << "no tinsmith::Error thrown";
  return ErrorKind::Internal;
}

// Input after finalize() left the Cdt finalized: mesh() returned the mesh
// without the new input and validate() read past the end of its vertex map.
TEST(CdtReview, InputAfterFinalizeNeedsAnotherFinalize) {
  Cdt cdt;
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  cdt.insertPoints(randomPoints(300, 3));
  cdt.finalize();
  ASSERT_TRUE(isValid(cdt));
  const std::size_t before = cdt.mesh().vertexCount();

  cdt.insertPoints(randomPoints(200, 5));
  EXPECT_EQ(kindOf([&] { (void)cdt.mesh(); }), ErrorKind::Usage);
  EXPECT_EQ(kindOf([&] { (void)cdt.validate(); }), ErrorKind::Usage);
  EXPECT_EQ(kindOf([&] { (void)cdt.toTinData(); }), ErrorKind::Usage);
  EXPECT_FALSE(cdt.meshVertex(VertexId(0)).valid());
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), before + 200);
  EXPECT_TRUE(cdt.meshVertex(VertexId(499)).valid());

  // A constraint between existing vertices, a polyline and domain rings too.
  cdt.insertConstraintSegment(VertexId(0), VertexId(1), road);
  EXPECT_EQ(kindOf([&] { (void)cdt.mesh(); }), ErrorKind::Usage);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  cdt.insertConstraint(std::vector<Point3>{{10, 10, 0}, {990, 990, 0}}, road);
  EXPECT_EQ(kindOf([&] { (void)cdt.validate(); }), ErrorKind::Usage);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
  cdt.addBoundary(std::vector<Point3>{{100, 100, 0}, {900, 100, 0}, {900, 900, 0}, {100, 900, 0}},
                  edge);
  EXPECT_EQ(kindOf([&] { (void)cdt.mesh(); }), ErrorKind::Usage);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_LT(cdt.mesh().vertexCount(), before + 200);  // the boundary dropped some
}

TEST(CdtReview, FinalizeTwiceAndReadingAgainStillWork) {
  Cdt cdt;
  cdt.insertPoints(randomPoints(300, 7));
  cdt.finalize();
  const TinData a = cdt.toTinData();
  cdt.finalize();  // nothing new
  EXPECT_TRUE(isValid(cdt));
  const TinData b = cdt.toTinData();
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(cdt.report().merges.size(), 0u);
}

// A polyline with a bad vertex in the middle left its earlier vertices
// inserted without their segments.
TEST(CdtReview, PolylineWithABadVertexChangesNothing) {
  Cdt cdt;
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
  cdt.insertPoints(randomPoints(300, 11));
  cdt.finalize();
  ASSERT_TRUE(isValid(cdt));
  const std::size_t inputs = cdt.inputVertexCount(), vertices = cdt.mesh().vertexCount();
  const std::size_t triangles = cdt.mesh().triangleCount();

  const std::vector<Point3> line{{10, 10, 0}, {500, 20, 0}, {NAN, 30, 0}, {990, 990, 0}};
  EXPECT_EQ(kindOf([&] { cdt.insertConstraint(line, road); }), ErrorKind::Input);
  const std::vector<Point3> far{{10, 10, 0}, {500, 20, 0}, {1e100, 30, 0}};
  EXPECT_EQ(kindOf([&] { cdt.insertConstraint(far, road, true); }), ErrorKind::Input);
  EXPECT_EQ(kindOf([&] { cdt.insertPoints(line, road); }), ErrorKind::Input);
  EXPECT_EQ(kindOf([&] { cdt.addBoundary(line, edge); }), ErrorKind::Input);
  // Nothing changed: the mesh stands, no finalize() needed.
  EXPECT_EQ(cdt.inputVertexCount(), inputs);
  ASSERT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), vertices);
  EXPECT_EQ(cdt.mesh().triangleCount(), triangles);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.mesh().vertexCount(), vertices);
  EXPECT_EQ(cdt.mesh().triangleCount(), triangles);  // the failed boundary bounds nothing

  // The same polyline without the bad vertex goes in whole.
  cdt.insertConstraint(std::vector<Point3>{{10, 10, 0}, {500, 20, 0}, {990, 990, 0}}, road);
  cdt.finalize();
  EXPECT_TRUE(isValid(cdt));
  EXPECT_EQ(cdt.inputVertexCount(), inputs + 3);
}

// With a boundary, a hole ring outside every boundary ring got odd depth and
// its inside became part of the domain.
TEST(CdtReview, HoleOutsideEveryBoundaryChangesNothing) {
  auto build = [](bool farHole, bool islandInFarHole, bool innerHole) {
    Cdt cdt;
    const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
    const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
    cdt.insertPoints(randomPoints(400, 17, 0, 100));
    cdt.addBoundary(square(10, 50), edge);
    if (farHole) cdt.addHole(square(55, 95), lake);
    if (islandInFarHole) cdt.addBoundary(square(65, 85), edge);
    if (innerHole) cdt.addHole(square(20, 30), lake);
    cdt.finalize();
    EXPECT_TRUE(isValid(cdt));
    return area(cdt.mesh());
  };
  EXPECT_NEAR(build(false, false, false), 1600, 1e-9);
  EXPECT_NEAR(build(true, false, false), 1600, 1e-9);
  EXPECT_NEAR(build(true, true, false), 1600 + 400, 1e-9);
  EXPECT_NEAR(build(false, false, true), 1600 - 100, 1e-9);
  EXPECT_NEAR(build(true, false, true), 1600 - 100, 1e-9);
  EXPECT_NEAR(build(true, true, true), 1600 + 400 - 100, 1e-9);
}

TEST(CdtReview, HolesWithoutABoundaryAndNestedRingsKeepTheirParity) {
  {
    Cdt cdt;
    const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
    cdt.insertPoints(square(0, 100));
    cdt.addHole(square(10, 50), lake);
    cdt.addHole(square(20, 30), lake);  // an island in the lake
    cdt.addHole(square(60, 90), lake);
    cdt.finalize();
    EXPECT_TRUE(isValid(cdt));
    EXPECT_NEAR(area(cdt.mesh()), 10000 - 1600 + 100 - 900, 1e-9);
  }
  {
    Cdt cdt;
    const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
    const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
    cdt.insertPoints(square(0, 100));
    cdt.addBoundary(square(10, 90), edge);
    cdt.addHole(square(20, 80), lake);
    cdt.addBoundary(square(30, 70), edge);  // an island in the lake
    cdt.addHole(square(40, 60), lake);      // a pond on the island
    cdt.finalize();
    EXPECT_TRUE(isValid(cdt));
    EXPECT_NEAR(area(cdt.mesh()), 6400 - 3600 + 1600 - 400, 1e-9);
  }
}

// What fromTinData's comment says: even a convex TIN's edge bounds the domain.
TEST(CdtReview, LoadedConvexTinKeepsItsEdgeAsTheDomain) {
  Cdt first;
  first.insertPoints(square(0, 100));
  first.insertPoint({50, 50, 1});
  first.finalize();
  Cdt again = Cdt::fromTinData(first.toTinData());
  const FeatureId lake = again.addFeature(FeatureKind::Hole, "lake");
  again.insertPoint({150, 50, 0});        // beyond the loaded edge: dropped
  again.addHole(square(120, 140), lake);  // outside the loaded edge: bounds nothing
  again.finalize();
  EXPECT_TRUE(isValid(again));
  EXPECT_NEAR(area(again.mesh()), 10000, 1e-9);
  EXPECT_EQ(again.mesh().vertexCount(), 5u);
  EXPECT_FALSE(again.meshVertex(VertexId(5)).valid());
}

// mesh(), report() and meshVertex() are const but built the mesh on first
// use: two first readers built it at once.
TEST(CdtReview, ConcurrentFirstReadersSeeOneMesh) {
  const std::size_t n = testing::kSanitized ? 20000 : 100000;
  constexpr int kReaders = 4;
  for (int round = 0; round < 3; ++round) {
    Cdt cdt;
    const FeatureId edge = cdt.addFeature(FeatureKind::Boundary, "edge");
    const FeatureId lake = cdt.addFeature(FeatureKind::Hole, "lake");
    const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
    cdt.insertPoints(randomPoints(n, 19 + round));
    cdt.insertPoints(randomPoints(n / 10, 19 + round));  // duplicates: merges
    cdt.addBoundary(std::vector<Point3>{{5, 5, 0}, {995, 20, 0}, {980, 990, 0}, {10, 970, 0}},
                    edge);
    cdt.addHole(square(300, 600), lake);
    cdt.insertConstraint(std::vector<Point3>{{-50, 500, 0}, {1050, 510, 0}}, road);
    cdt.finalize();

    std::latch start(kReaders);
    std::vector<TinData> tins(kReaders);
    std::vector<std::size_t> merges(kReaders), dropped(kReaders);
    std::vector<std::uint32_t> vertexOf(kReaders);
    std::vector<std::thread> readers;
    for (int k = 0; k < kReaders; ++k) {
      readers.emplace_back([&, k] {
        start.arrive_and_wait();
        switch (k % 3) {
          case 0:
            tins[k] = cdt.mesh().toTinData();
            break;
          case 1:
            dropped[k] = cdt.report().dropped.size();
            break;
          default:
            vertexOf[k] = cdt.meshVertex(VertexId(7)).value;
            break;
        }
        tins[k] = cdt.toTinData();
        merges[k] = cdt.report().merges.size();
        dropped[k] = cdt.report().dropped.size();
        vertexOf[k] = cdt.meshVertex(VertexId(7)).value;
      });
    }
    for (auto& t : readers) t.join();
    ASSERT_TRUE(isValid(cdt));
    const TinData expected = cdt.toTinData();
    EXPECT_GT(expected.triangles.size(), n / 2);
    for (int k = 0; k < kReaders; ++k) {
      EXPECT_EQ(tins[k].vertices, expected.vertices) << "reader " << k;
      EXPECT_EQ(tins[k].triangles, expected.triangles) << "reader " << k;
      EXPECT_EQ(tins[k].constrainedEdges, expected.constrainedEdges) << "reader " << k;
      EXPECT_EQ(merges[k], cdt.report().merges.size());
      EXPECT_EQ(dropped[k], cdt.report().dropped.size());
      EXPECT_EQ(vertexOf[k], cdt.meshVertex(VertexId(7)).value);
    }
  }
}

// The validator's chain search looked each vertex up in a list of those seen:
// a constraint running through n vertices took O(n^2) steps (and a feature
// bent by a forced crossing, searched without the distance bound, up to
// O(n^3) over its segments). Counted in steps, not timed.
TEST(CdtReview, ChainSearchOfALongConstraintIsLinear) {
  constexpr int n = 20000;
  Cdt cdt;
  const FeatureId contour = cdt.addFeature(FeatureKind::Contour, "contour");
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  std::vector<Point3> line;  // a contour of n vertices on y = 0
  for (int i = 0; i < n; ++i) line.push_back({static_cast<double>(i), 0, 100});
  std::vector<Point3> beside;  // points off the line, so the triangles are many
  for (int i = 0; i < n; i += 97) {
    beside.push_back({i + 0.5, 3, 90});
    beside.push_back({i + 0.25, -2, 110});
  }
  cdt.insertPoints(beside);
  cdt.insertConstraint(line, contour);
  // One road segment along the whole contour: a chain of n edges.
  cdt.insertConstraint(std::vector<Point3>{{-1, 0, 100}, {n, 0, 100}}, road);
  cdt.finalize();
  std::size_t steps = 0;
  const ValidationReport r = CdtTestAccess::validate(cdt, steps);
  EXPECT_TRUE(r.ok) << r.summary();
  EXPECT_EQ(cdt.mesh().vertexCount(), n + 2 + beside.size());
  // Each vertex of a chain is reached once and its 8 adjacency entries (2
  // edges, 2 half-edges, 2 features) are looked at: at most 16 n in all.
  EXPECT_GT(steps, 8u * n);
  EXPECT_LT(steps, 64u * n);
}

// rerouteThrough did not check that the edge it reroutes exists, nor bound
// how deep reroutes nest (each inserts segments whose crossings may reroute
// again; insertSegment's guards are per call), so adversarial input could
// overflow the stack. Natural input nests a reroute or two deep; with the
// bound lowered below what an input needs, finalize() throws internalError.
// (The crossing of CdtConstraintRegression.CrossingBesideASliverStaysOnBothLines:
// it goes in beside a sliver and R–L's constraint is rerouted through it.)
TEST(CdtReview, RerouteNestingIsBoundedByAnInternalError) {
  auto build = [](Cdt& cdt) {
    cdt.insertPoints(sliver::points());
    const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
    const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
    cdt.insertConstraintSegment(VertexId(2), VertexId(0), road);
    cdt.insertConstraint(
        std::vector<Point3>{sliver::A, sliver::B}, river);
  };
  Cdt natural;
  build(natural);
  natural.finalize();
  EXPECT_TRUE(isValid(natural));
  const std::size_t depth = CdtTestAccess::deepestReroute(natural);
  ASSERT_GE(depth, 1u);
  EXPECT_LE(depth, 4u);

  Cdt enough;
  CdtTestAccess::setRerouteDepthLimit(enough, depth);
  build(enough);
  enough.finalize();
  EXPECT_TRUE(isValid(enough));
  EXPECT_EQ(enough.toTinData().triangles, natural.toTinData().triangles);

  Cdt bounded;
  CdtTestAccess::setRerouteDepthLimit(bounded, depth - 1);
  build(bounded);
  EXPECT_EQ(kindOf([&] { bounded.finalize(); }), ErrorKind::Internal);
}

}  // namespace
}  // namespace tinsmith
