// Surface queries: exact reproduction of a plane, locate on edges/vertices,
// outside points, holes, batched and grid queries, profiles; on CDT output and
// on a mesh rebuilt from TinData.
#include "core/surface/surface.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/cdt/cdt.hpp"
#include "tests/core/cdt_test_util.hpp"

namespace tinsmith {
namespace {

// z = 2x − 3y + 5 sampled at random points: every query must reproduce it.
double plane(double x, double y) { return 2 * x - 3 * y + 5; }

TinData planeTin(bool withHole) {
  Cdt cdt;
  std::vector<Point3> pts;
  for (const Point3& p : testing::randomPoints(2000, 5)) pts.push_back({p.x, p.y, plane(p.x, p.y)});
  for (double c : {0.0, 1000.0}) {
    pts.push_back({c, 0, plane(c, 0)});
    pts.push_back({c, 1000, plane(c, 1000)});
  }
  cdt.insertPoints(pts);
  if (withHole) {
    const FeatureId h = cdt.addFeature(FeatureKind::Hole, "hole");
    std::vector<Point3> ring{{400, 400, 0}, {600, 400, 0}, {600, 600, 0}, {400, 600, 0}};
    for (auto& p : ring) p.z = plane(p.x, p.y);
    cdt.addHole(ring, h);
  }
  cdt.finalize();
  EXPECT_TRUE(testing::isValid(cdt));
  return cdt.toTinData();
}

TEST(Surface, ReproducesAPlane) {
  const Surface s(planeTin(false));
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> d(0, 1000);
  for (int i = 0; i < 1000; ++i) {
    const Point2 p{d(rng), d(rng)};
    const auto z = s.z(p);
    ASSERT_TRUE(z.has_value());
    EXPECT_NEAR(*z, plane(p.x, p.y), 1e-6);
  }
  const auto sm = s.sample({500, 500});
  ASSERT_TRUE(sm);
  EXPECT_NEAR(sm->slope, std::sqrt(13.0), 1e-9);
  EXPECT_NEAR(sm->normal.x, -2 / std::sqrt(14.0), 1e-9);
  EXPECT_NEAR(sm->normal.y, 3 / std::sqrt(14.0), 1e-9);
  EXPECT_NEAR(sm->normal.z, 1 / std::sqrt(14.0), 1e-9);
  EXPECT_NEAR(sm->slopeDegrees, std::atan(std::sqrt(13.0)) * 180 / M_PI, 1e-9);
}

TEST(Surface, VerticesEdgesAndOutside) {
  const TinData tin = planeTin(false);
  const Surface s(tin);
  for (std::size_t i = 0; i < tin.vertices.size(); i += 97) {
    const auto z = s.z(tin.vertices[i].xy());
    ASSERT_TRUE(z);
    EXPECT_NEAR(*z, tin.vertices[i].z, 1e-9);
  }
  EXPECT_FALSE(s.z({-1, 500}));
  EXPECT_FALSE(s.z({500, 1000.5}));
  EXPECT_FALSE(s.z({NAN, 1}));
  EXPECT_TRUE(s.z({0, 500}));  // on the hull edge
}

TEST(Surface, HoleIsOutside) {
  const Surface s(planeTin(true));
  EXPECT_FALSE(s.z({500, 500}));
  EXPECT_TRUE(s.z({300, 300}));
  const std::vector<Point2> line{{100, 500}, {900, 500}};
  const auto prof = s.profile(line);
  ASSERT_GT(prof.size(), 10u);
  bool sawInside = false, sawOutside = false;
  for (std::size_t i = 0; i < prof.size(); ++i) {
    if (i) {
      EXPECT_GE(prof[i].distance, prof[i - 1].distance);
    }
    if (prof[i].inside) {
      sawInside = true;
      EXPECT_NEAR(prof[i].point.z, plane(prof[i].point.x, prof[i].point.y), 1e-6);
    } else {
      sawOutside = true;
      EXPECT_GT(prof[i].point.x, 399.999);
      EXPECT_LT(prof[i].point.x, 600.001);
    }
  }
  EXPECT_TRUE(sawInside);
  EXPECT_TRUE(sawOutside);
  EXPECT_DOUBLE_EQ(prof.back().distance, 800.0);
}

TEST(Surface, BatchedAndGridMatchSingleQueries) {
  const Surface s(planeTin(true));
  SampleGrid g;
  g.x0 = -10;
  g.y0 = -10;
  g.dx = 7.3;
  g.dy = 9.1;
  g.nx = 150;
  g.ny = 120;
  const std::vector<double> zs = s.zGrid(g);
  ASSERT_EQ(zs.size(), g.nx * g.ny);
  for (std::size_t j = 0; j < g.ny; ++j) {
    for (std::size_t i = 0; i < g.nx; ++i) {
      const Point2 p{g.x0 + i * g.dx, g.y0 + j * g.dy};
      const auto single = s.z(p);
      const double batched = zs[j * g.nx + i];
      ASSERT_EQ(single.has_value(), !std::isnan(batched)) << p.x << " " << p.y;
      if (single) {
        EXPECT_NEAR(*single, batched, 1e-9);
      }
    }
  }
}

TEST(Surface, ProfileCrossesEveryEdge) {
  const Surface s(planeTin(false));
  const std::vector<Point2> line{{10, 10}, {990, 20}, {500, 900}};
  const auto prof = s.profile(line);
  ASSERT_GT(prof.size(), 20u);
  const double total = std::hypot(980, 10) + std::hypot(490, 880);
  EXPECT_NEAR(prof.back().distance, total, 1e-9);
  for (const auto& p : prof) {
    EXPECT_TRUE(p.inside);
    EXPECT_NEAR(p.point.z, plane(p.point.x, p.point.y), 1e-6);
  }
}

}  // namespace
}  // namespace tinsmith
