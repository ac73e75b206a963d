// River profiles: draping, descent downstream (digitised either way), road
// smoothing. Pure functions on polylines with a surface callback.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/base/error.hpp"
#include "ingest/build/line_profile.hpp"

namespace tinsmith::ingest {
namespace {

std::vector<Point3> line(std::initializer_list<double> zs) {
  std::vector<Point3> out;
  double x = 0;
  for (double z : zs) out.push_back({x++ * 10.0, 0.0, z});
  return out;
}

TEST(RiverDescent, AlreadyDescendingRiverIsUntouched) {
  auto river = line({100, 99, 99, 95, 80});
  const auto before = river;
  const auto r = enforceDescent(river);
  EXPECT_FALSE(r.reversed);
  EXPECT_EQ(r.adjusted, 0u);
  EXPECT_EQ(river, before);
}

TEST(RiverDescent, ADamIsLeveledByTheLeastTotalChange) {
  auto river = line({100, 90, 96, 80, 70});  // 96 after 90 is a rise
  const auto r = enforceDescent(river);
  EXPECT_FALSE(r.reversed);
  EXPECT_TRUE(descends(river));
  // Equal spacing: the violating pair (90, 96) pools to its mean 93.
  EXPECT_DOUBLE_EQ(river[1].z, 93.0);
  EXPECT_DOUBLE_EQ(river[2].z, 93.0);
  EXPECT_EQ(river[0].z, 100.0);
  EXPECT_EQ(river[3].z, 80.0);
  EXPECT_EQ(r.adjusted, 2u);
  EXPECT_DOUBLE_EQ(r.maxAdjustment, 3.0);
  // Where: the first downstream of the two changed by 3 m (90 raised to 93).
  EXPECT_EQ(r.maxAt.x, 10.0);
  EXPECT_DOUBLE_EQ(r.maxFrom, 90.0);
  EXPECT_DOUBLE_EQ(r.maxTo, 93.0);
}

TEST(RiverDescent, RiverDigitisedUpstreamIsDetectedAndDescendsTowardsItsFirstVertex) {
  // Digitised from the sea upwards, with a pit on the way up.
  auto river = line({5, 12, 9, 20, 35, 33, 50});
  const auto r = enforceDescent(river);
  EXPECT_TRUE(r.reversed);
  EXPECT_TRUE(descends(river));
  for (std::size_t i = 1; i < river.size(); ++i) EXPECT_GE(river[i].z, river[i - 1].z) << i;
  EXPECT_EQ(river.front().z, 5.0);
  EXPECT_EQ(river.back().z, 50.0);
  EXPECT_DOUBLE_EQ(river[1].z, 10.5);
  EXPECT_DOUBLE_EQ(river[2].z, 10.5);
  EXPECT_DOUBLE_EQ(river[4].z, 34.0);
  EXPECT_EQ(r.adjusted, 4u);
  // x, y and the vertex order are never touched.
  for (std::size_t i = 0; i < river.size(); ++i)
    EXPECT_EQ(river[i].x, 10.0 * static_cast<double>(i));
}

TEST(RiverDescent, WeightsFollowLengthNotVertexCount) {
  // A densely digitised stretch (many vertices over 1 m) must not outvote a
  // long sparse one: the pooled level sits near the long segment's end.
  std::vector<Point3> river{{0, 0, 100}, {1000, 0, 50}};
  for (int i = 1; i <= 20; ++i) river.push_back({1000 + 0.05 * i, 0, 60});
  river.push_back({1001.5, 0, 0});
  enforceDescent(river);
  EXPECT_TRUE(descends(river));
  EXPECT_LT(river[1].z, 52.0);  // mostly the 50 of the long-weighted vertex
}

TEST(RiverDescent, RandomProfilesAlwaysDescendAndMonotoneOnesStay) {
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0, 3);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Point3> river;
    const int n = 2 + trial % 50;
    for (int i = 0; i < n; ++i) river.push_back({i * 7.0, 0, 200 - i * 0.5 + noise(rng)});
    const auto r = enforceDescent(river);
    EXPECT_TRUE(descends(river));
    auto again = river;
    EXPECT_EQ(enforceDescent(again).adjusted, 0u);
    EXPECT_EQ(again, river);
    (void)r;
  }
}

TEST(Drape, TakesZFromTheSurfaceAndInterpolatesOutside) {
  std::vector<Point3> road{{-10, 0, 0}, {0, 0, 0}, {10, 0, 0}, {20, 0, 0}, {30, 0, 0}, {40, 0, 0}};
  // A plane z = 100 + x defined only for 0 <= x <= 10 and x >= 30.
  ZLookup surface = [](double x, double) -> std::optional<double> {
    if ((x >= 0 && x <= 10) || x >= 30) return 100 + x;
    return std::nullopt;
  };
  const auto r = drape(road, surface, "road.geojson, feature 0");
  EXPECT_EQ(r.draped, 4u);
  EXPECT_EQ(r.outside, 2u);
  EXPECT_EQ(road[0].z, 100.0);  // before the first known: nearest known
  EXPECT_EQ(road[2].z, 110.0);
  EXPECT_DOUBLE_EQ(road[3].z, 120.0);  // between 110 and 130 by length
  EXPECT_EQ(road[5].z, 140.0);
}

TEST(Drape, ALineEntirelyOffTheSurfaceIsAGeometryErrorNamingIt) {
  std::vector<Point3> l{{0, 0, 0}, {1, 1, 0}};
  try {
    drape(
        l, [](double, double) { return std::optional<double>{}; }, "streams.geojson, feature 4");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Geometry);
    EXPECT_NE(std::string(e.what()).find("streams.geojson, feature 4"), std::string::npos);
  }
}

TEST(Densify, NoSegmentLongerThanTheSpacingAndOriginalVerticesKept) {
  std::vector<Point3> l{{0, 0, 0}, {25, 0, 25}, {25, 3, 28}};
  densify(l, 10);
  ASSERT_EQ(l.size(), 5u);
  EXPECT_EQ(l[0], (Point3{0, 0, 0}));
  EXPECT_EQ(l[3], (Point3{25, 0, 25}));
  EXPECT_EQ(l[4], (Point3{25, 3, 28}));
  for (std::size_t i = 1; i < l.size(); ++i)
    EXPECT_LE(std::hypot(l[i].x - l[i - 1].x, l[i].y - l[i - 1].y), 10.0 + 1e-12);
  EXPECT_DOUBLE_EQ(l[1].z, 25.0 / 3.0);
}

TEST(RoadSmoothing, SpikesGoAndTheProfileStaysNearTheTerrain) {
  std::vector<Point3> road;
  for (int i = 0; i <= 40; ++i) road.push_back({i * 5.0, 0, 1600 + i * 0.5});
  road[10].z += 25;  // a spike from draping over a mis-surveyed point
  road[30].z -= 18;  // and a pit
  const auto r = smoothAlongLength(road, 30.0, 2.0);
  EXPECT_EQ(r.spikesRemoved, 2u);
  EXPECT_GE(r.maxChange, 18.0);
  for (std::size_t i = 0; i < road.size(); ++i)
    EXPECT_NEAR(road[i].z, 1600 + static_cast<double>(i) * 0.5, 0.26) << i;
  EXPECT_EQ(road.front().z, 1600.0);
  EXPECT_EQ(road.back().z, 1620.0);
  // No step between neighbours is larger than the grade allows.
  for (std::size_t i = 1; i < road.size(); ++i) EXPECT_LT(std::abs(road[i].z - road[i - 1].z), 1.0);
}

// Regression: Red Butte's stream 8 starts where streams 6 and 7 end; each
// descended on its own, the confluence took stream 6's end (1999.487 m) and
// stream 8 rose from it to its own 1999.757 m before descending.
TEST(RiverDescent, AnOutflowDescendsFromTheConfluenceItsInflowsEndAt) {
  std::vector<Point3> inflow{{0, 0, 10}, {10, 0, 5}};
  std::vector<Point3> other{{10, 10, 9}, {10, 0, 5.5}};
  std::vector<Point3> outflow{{10, 0, 6}, {15, 0, 5.8}, {18, 0, 5.9}, {20, 0, 3}};
  for (auto* line : {&inflow, &other, &outflow}) enforceDescent(*line);
  const double before = outflow[1].z;
  ASSERT_GT(before, inflow.back().z)
      << "the outflow does not rise from the confluence: nothing to test";
  std::vector<Point3> reversedOutflow(outflow.rbegin(), outflow.rend());  // digitised upstream
  std::vector<Point3> inflow2 = inflow, other2 = other;
  EXPECT_GT(reconcileConfluences({&inflow, &other, &outflow}, {false, false, false}), 0u);
  EXPECT_GT(reconcileConfluences({&inflow2, &other2, &reversedOutflow}, {false, false, true}), 0u);
  for (const auto* line : {&inflow, &other, &outflow}) EXPECT_TRUE(descends(*line));
  // Every end at the confluence has the lowest z there, and the outflow
  // never rises from it.
  EXPECT_EQ(inflow.back().z, 5);
  EXPECT_EQ(other.back().z, 5);
  EXPECT_EQ(outflow.front().z, 5);
  for (std::size_t k = 1; k < outflow.size(); ++k) EXPECT_LE(outflow[k].z, outflow[k - 1].z);
  EXPECT_EQ(outflow.back().z, 3);
  std::vector<Point3> back(reversedOutflow.rbegin(), reversedOutflow.rend());
  EXPECT_EQ(back, outflow);
}

}  // namespace
}  // namespace tinsmith::ingest
