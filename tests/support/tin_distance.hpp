// Distances to a TIN for the tests that measure decoded tiles against it
// (3D Tiles and Cesium terrain): geodetic positions back to the project CRS
// through PROJ, and the 3-D distance from a point to the nearest TIN triangle.
#pragma once

#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/encode/frames.hpp"
#include "core/tiles/surface_difference.hpp"

namespace tinsmith::test {

/// WGS84 geodetic (ellipsoidal heights) back to the project CRS, through PROJ.
class ToProject {
 public:
  explicit ToProject(const std::string& crs) {
    OGRSpatialReference src, dst;
    src.importFromEPSG(4979);
    src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    dst.SetFromUserInput(crs.c_str());
    dst.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    ct_.reset(OGRCreateCoordinateTransformation(&src, &dst));
  }
  Point3 operator()(const encode::Geodetic& g) const {
    double x = g.lon, y = g.lat, z = g.height;
    EXPECT_TRUE(ct_->Transform(1, &x, &y, &z));
    return {x, y, z};
  }

 private:
  struct Destroy {
    void operator()(OGRCoordinateTransformation* c) const {
      OGRCoordinateTransformation::DestroyCT(c);
    }
  };
  std::unique_ptr<OGRCoordinateTransformation, Destroy> ct_;
};

/// The closest point of triangle abc to p (Ericson, Real-Time Collision
/// Detection, 5.1.5), its distance.
inline double pointTriangleDistance(const Point3& p, const Point3& a, const Point3& b,
                                    const Point3& c) {
  const auto sub = [](const Point3& u, const Point3& v) {
    return Point3{u.x - v.x, u.y - v.y, u.z - v.z};
  };
  const auto dot = [](const Point3& u, const Point3& v) {
    return u.x * v.x + u.y * v.y + u.z * v.z;
  };
  const auto at = [&](const Point3& q) { return std::sqrt(dot(sub(p, q), sub(p, q))); };
  const auto along = [](const Point3& o, const Point3& d, double t) {
    return Point3{o.x + t * d.x, o.y + t * d.y, o.z + t * d.z};
  };
  const Point3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return at(a);
  const Point3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return at(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(along(a, ab, d1 / (d1 - d3)));
  const Point3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return at(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(along(a, ac, d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return at(along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const double denom = 1 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return at({a.x + ab.x * v + ac.x * w, a.y + ab.y * v + ac.y * w, a.z + ab.z * v + ac.z * w});
}

/// The 3-D distance from p (project CRS) to the TIN, looked for within
/// `reach` metres; nullopt when no TIN triangle is that near (p off the TIN).
inline std::optional<double> distanceToTin(const Point3& p, const tiles::TinIndex& index,
                                           double reach, std::vector<std::uint32_t>& scratch) {
  const TinData& tin = index.tin();
  index.overlapping({p.x - reach, p.y - reach, p.x + reach, p.y + reach}, scratch);
  std::optional<double> best;
  for (std::uint32_t t : scratch) {
    const auto& tri = tin.triangles[t];
    const double d =
        pointTriangleDistance(p, tin.vertices[tri[0]], tin.vertices[tri[1]], tin.vertices[tri[2]]);
    if (!best || d < *best) best = d;
  }
  return best;
}

}  // namespace tinsmith::test
