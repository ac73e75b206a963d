// Crossing resolution step by step (core/cdt/crossing_resolution.cpp): for
// each step of cdt::CrossingStep, an input whose crossings need it — most
// found by the CDT fuzzer (tests/fuzz) and replayed here with its operations
// as literals — checked valid, with the step's count from CdtTestAccess.
#include <gtest/gtest.h>

#include <vector>

#include "core/cdt/cdt.hpp"
#include "core/cdt/cdt_test_access.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

using cdt::CrossingStep;
using testing::isValid;

/// One operation of the fuzz target (tests/fuzz/cdt_fuzz.cpp): op 0–4
/// inserts points of feature op, 5–6 a polyline of feature `feature`, 7 a
/// closed one, 8 a boundary ring, 9 a hole ring; kFinalize calls finalize().
struct FuzzOp {
  int op;
  int feature;
  std::vector<Point3> points;
};
constexpr int kFinalize = -1;

/// Replays ops into a Cdt registered with the fuzz target's features (six of
/// kinds 0–5, then a boundary and a hole), and finalizes it.
Cdt replay(double snapTolerance, std::size_t splitMinPoints, const std::vector<FuzzOp>& ops) {
  CdtOptions options;
  options.snapTolerance = snapTolerance;
  options.splitMinPoints = splitMinPoints;
  Cdt cdt(options);
  std::vector<FeatureId> features;
  for (int k = 0; k < 6; ++k) {
    features.push_back(cdt.addFeature(static_cast<FeatureKind>(k), "fuzz"));
  }
  const FeatureId boundary = cdt.addFeature(FeatureKind::Boundary, "boundary");
  const FeatureId hole = cdt.addFeature(FeatureKind::Hole, "hole");
  for (const FuzzOp& o : ops) {
    if (o.op == kFinalize) {
      cdt.finalize();
    } else if (o.op <= 4) {
      cdt.insertPoints(o.points, features[o.op]);
    } else if (o.op <= 7) {
      cdt.insertConstraint(o.points, features[o.feature], o.op == 7);
    } else if (o.op == 8) {
      cdt.addBoundary(o.points, boundary);
    } else {
      cdt.addHole(o.points, hole);
    }
  }
  cdt.finalize();
  return cdt;
}

std::size_t placedBy(const Cdt& cdt, CrossingStep step) {
  return CdtTestAccess::crossingsPlacedBy(cdt, step);
}

// A closed break line whose vertices repeat at one corner: a crossing falls
// within the snap tolerance of the far end of the segment being inserted,
// beyond slivers, and the crossed constraint is rerouted through that end.
TEST(CdtCrossingSteps, CrossingAtTheFarEndOfTheSegmentReroutesThroughIt) {
  const Cdt cdt = replay(1.5, 0,
                         {{7,
                           0,
                           {{6999986, 6999993, 6},
                            {7000000, 7000018, 69},
                            {6999998, 7000015, 17},
                            {7000002, 7000005, 27},
                            {6999992, 7000005, 0},
                            {6999980, 6999980, 0},
                            {6999980, 6999980, 0},
                            {6999980, 6999980, 0},
                            {6999980, 6999980, 0},
                            {6999980, 6999980, 0}}}});
  EXPECT_GT(placedBy(cdt, CrossingStep::SegmentEnd), 0u);
  EXPECT_TRUE(isValid(cdt));
}

// Found by the fuzzer (seed crossing-beyond-a-sliver-recovered-by-flips): one
// input needs four steps — crossings that split their edge, one within the
// tolerance of a vertex, one nudged across an edge by a few ulps, and one
// beyond a sliver, recovered by flips.
TEST(CdtCrossingSteps, CrossingBeyondASliverIsRecoveredByFlips) {
  const Cdt cdt = replay(0.0, 50000,
                         {{8,
                           8,
                           {{7000014, 6999987, 24},
                            {6999982.0000000009, 7000015, 83},
                            {6999980.9999999991, 7000004, 35},
                            {7000015, 6999985, 0},
                            {6999980, 6999980.0000000009, 24},
                            {6999988, 7000019, 56},
                            {7000018, 6999980, 27},
                            {7000004, 6999985, 37},
                            {6999986.9999999991, 6999987, 24},
                            {7000014.9999999991, 6999985, 42}}},
                          {1,
                           1,
                           {{6999993, 7000015, 10},
                            {6999980, 6999980, 0},
                            {6999980, 6999980, 0},
                            {6999980, 6999980, 0}}}});
  EXPECT_GT(placedBy(cdt, CrossingStep::SplitEdge), 0u);
  EXPECT_GT(placedBy(cdt, CrossingStep::NearVertex), 0u);
  EXPECT_GT(placedBy(cdt, CrossingStep::Nudged), 0u);
  EXPECT_GT(placedBy(cdt, CrossingStep::BeyondSliver), 0u);
  EXPECT_TRUE(isValid(cdt));
}

// The self-crossing ring of
// CdtConstraintRegression.SelfCrossingRingWithAnUlpOffVertexKeepsEveryCrossing:
// a rounded crossing falls outside a sliver beside the crossed edge and goes
// into the triangle on the edge's other side.
TEST(CdtCrossingSteps, CrossingOutsideASliverGoesInBesideTheEdge) {
  const Cdt cdt = replay(0.0, 50000,
                         {{7,
                           3,
                           {{6999998.9000000004, 6999998.9000000004, 0},
                            {6999998.5, 6999998.4000000004, 27},
                            {6999998.5000000009, 7000001.5, 49},
                            {6999998.5, 6999998.5, 58},
                            {6999998.4000000004, 6999999.5, 53},
                            {6999999, 7000001.7999999998, 0},
                            {6999998, 6999998, 0}}}});
  EXPECT_GT(placedBy(cdt, CrossingStep::BesideEdge), 0u);
  EXPECT_TRUE(isValid(cdt));
}

// Found by the fuzzer (seed crossing-near-the-origin-beside-a-collinear-sliver):
// near the origin, a sliver's apex lies on a crossed constraint and is taken
// into it instead of a new vertex.
TEST(CdtCrossingSteps, SliverApexOnTheCrossedEdgeJoinsItsConstraint) {
  const Cdt cdt = replay(
      0.0, 50000,
      {{0, 0, {{-2, -2, 0}}},
       {2,
        2,
        {{0.20000000000000001, 0.20000000000000001, 53},
         {-1.6000000000000001, -2, 97},
         {-1.9999999999999998, -1.8999999999999999, 53},
         {-1.1000000000000003, -1.1000000000000001, 53}}},
       {0, 0, {{-0.60000000000000009, -0.60000000000000009, 39}}},
       {7,
        0,
        {{-1.9000000000000001, 1, 24},
         {-0.80000000000000016, -0.80000000000000004, 95},
         {-1.1000000000000001, -1.1000000000000001, 45},
         {-2, 1.2000000000000002, 15},
         {1.6000000000000001, 1.6000000000000001, 42},
         {-1.8999999999999999, -1.7999999999999998, 9},
         {0.30000000000000004, 1.2000000000000002, 32},
         {-0.50000000000000011, -2, 9},
         {2, 1.5, 15},
         {-1.9000000000000004, -1.1000000000000001, 97},
         {1.9000000000000001, 1.2000000000000004, 0},
         {-0.30000000000000004, -0.39999999999999997, 53}}},
       {kFinalize, 0, {}},
       {0, 0, {{-2.0000000000000004, -2, 19}}},
       {5,
        2,
        {{1.3999999999999999, 2, 9},
         {-1.1000000000000001, -1.1000000000000001, 24},
         {1.7999999999999998, 1.8, 95},
         {-2.0000000000000004, -2, 3},
         {-2.0000000000000004, -2, 3},
         {-2, -0.40000000000000002, 16},
         {-0.40000000000000002, -1.5, 0},
         {-2, -2, 0},
         {1.5000000000000002, -1.4999999999999998, 27}}},
       {6,
        2,
        {{1.8, -1.6000000000000001, 97},
         {-1.9999999999999998, -1.8999999999999999, 21},
         {1.4999999999999998, -1, 42},
         {-1.1000000000000003, -1.1000000000000001, 43},
         {-2, -2, 58},
         {-0.39999999999999997, -1.2000000000000002, 19},
         {-0.39999999999999997, -1.5, 16},
         {-1.5, -1.5, 0},
         {-2, -2, 16}}},
       {1,
        1,
        {{-1.5, 1.5, 41},
         {-0.70000000000000007, -0.40000000000000002, 0},
         {-2, -2, 48},
         {-2, 1.6000000000000003, 37},
         {0.20000000000000001, 0.70000000000000007, 0},
         {-0.30000000000000004, -0.39999999999999997, 37},
         {1.7, -1.9000000000000001, 78},
         {1.7000000000000002, 1.7000000000000002, 0},
         {-2, -0.70000000000000007, 17}}},
       {0, 0, {{-2, -0.70000000000000007, 77}}},
       {2, 2, {{0.20000000000000001, 0.70000000000000007, 0}, {-2, -2, 0}}}});
  EXPECT_GT(placedBy(cdt, CrossingStep::SliverApex), 0u);
  EXPECT_TRUE(isValid(cdt));
}

// Points a tenth of a metre apart inside a boundary ring, a break line among
// them: a crossing beside slivers that no other step can place goes to the
// nearest vertex around the crossed edge.
TEST(CdtCrossingSteps, CrossingNoOtherStepPlacesGoesToTheNearestVertex) {
  const Cdt cdt = replay(5.0000000000000002e-05, 50000,
                         {{8,
                           8,
                           {{6999998, 6999999.0999999996, 40},
                            {6999999.7999999998, 6999999.9000000004, 92},
                            {7000000, 7000000.2999999998, 28},
                            {7000001.0999999996, 7000001.4000000004, 38},
                            {6999999.1999999993, 6999999.5, 100},
                            {7000000.7000000011, 7000001.0000000009, 67},
                            {7000001.3999999994, 7000000.7999999998, 0},
                            {7000000.4000000004, 7000001, 40},
                            {7000001.9999999991, 7000000.7000000002, 81},
                            {6999999.5, 7000002, 29}}},
                          {2,
                           2,
                           {{6999999.2999999998, 6999999.5999999996, 52},
                            {6999998.0999999996, 6999998, 27},
                            {6999999.8000000007, 7000001.9000000004, 66},
                            {7000001.3999999994, 7000001.0999999996, 47},
                            {6999998.7000000002, 6999999.2999999998, 33}}},
                          {5,
                           3,
                           {{7000000.0999999987, 6999999.5999999996, 61},
                            {7000000.2000000002, 7000000.5999999996, 89}}},
                          {2,
                           2,
                           {{6999999.0000000009, 7000000.0000000009, 5},
                            {7000000.0999999996, 6999998.4000000013, 0},
                            {6999998, 6999998, 0},
                            {6999998, 6999998, 0}}}});
  EXPECT_GT(placedBy(cdt, CrossingStep::NearestVertex), 0u);
  EXPECT_TRUE(isValid(cdt));
}

}  // namespace
}  // namespace tinsmith
