// Regressions found by a review of core/cdt/cdt.cpp: input added after
// finalize(), the nesting of constraint reroutes, the validator's chain
// search, concurrent readers of a finalized Cdt, holes outside every boundary
// and polylines with a bad vertex.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using testing::isValid;
using testing::randomPoints;

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

}  // namespace
}  // namespace tinsmith
