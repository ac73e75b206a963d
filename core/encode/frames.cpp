// Earth frames on GeographicLib's WGS84 geocentric conversion; see frames.hpp.
#include "core/encode/frames.hpp"

#include <GeographicLib/Geocentric.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "core/base/error.hpp"

namespace tinsmith::encode {
namespace {

void checkGeodetic(const Geodetic& g) {
  if (!std::isfinite(g.lon) || !std::isfinite(g.lat) || !std::isfinite(g.height) ||
      std::abs(g.lat) > 90.0) {
    throw inputError("geodetic position (lon " + std::to_string(g.lon) + "°, lat " +
                         std::to_string(g.lat) + "°, h " + std::to_string(g.height) +
                         " m) is not on the globe",
                     {}, "give a finite longitude, a latitude in [-90°, 90°] and a finite height");
  }
}

}  // namespace

Point3 geodeticToEcef(const Geodetic& g) {
  checkGeodetic(g);
  Point3 p;
  GeographicLib::Geocentric::WGS84().Forward(g.lat, g.lon, g.height, p.x, p.y, p.z);
  return p;
}

Geodetic ecefToGeodetic(const Point3& ecef) {
  if (!std::isfinite(ecef.x) || !std::isfinite(ecef.y) || !std::isfinite(ecef.z)) {
    throw inputError("ECEF position is not finite");
  }
  Geodetic g;
  GeographicLib::Geocentric::WGS84().Reverse(ecef.x, ecef.y, ecef.z, g.lat, g.lon, g.height);
  return g;
}

Matrix4 zUpContentRootMatrix(const Point3& centre) {
  // T⁻¹(x, y, z) = (x, z, −y); columns of T⁻¹ are its images of the axes, the
  // last column is T⁻¹ · centre.
  return {1.0,      0.0,      0.0,       0.0,  //
          0.0,      0.0,      -1.0,      0.0,  //
          0.0,      1.0,      0.0,       0.0,  //
          centre.x, centre.z, -centre.y, 1.0};
}

EnuFrame::EnuFrame(const Geodetic& origin) : origin_(origin) {
  checkGeodetic(origin);
  std::vector<double> m(9);
  GeographicLib::Geocentric::WGS84().Forward(origin.lat, origin.lon, origin.height, originEcef_.x,
                                             originEcef_.y, originEcef_.z, m);
  for (std::size_t i = 0; i < 9; ++i) rotation_[i] = m[i];
}

Point3 EnuFrame::fromGeodetic(const Geodetic& g) const {
  const Point3 p = geodeticToEcef(g);
  const double d[3] = {p.x - originEcef_.x, p.y - originEcef_.y, p.z - originEcef_.z};
  // rotation_ is ENU → ECEF and orthogonal, so ECEF → ENU is its transpose.
  const auto& r = rotation_;
  return {r[0] * d[0] + r[3] * d[1] + r[6] * d[2], r[1] * d[0] + r[4] * d[1] + r[7] * d[2],
          r[2] * d[0] + r[5] * d[1] + r[8] * d[2]};
}

Matrix4 EnuFrame::toEcefMatrix() const {
  const auto& r = rotation_;
  // Column j of the rotation (row-major r[3i + j]) is the ECEF direction of
  // ENU axis j.
  return {r[0],          r[3],          r[6],          0.0,  //
          r[1],          r[4],          r[7],          0.0,  //
          r[2],          r[5],          r[8],          0.0,  //
          originEcef_.x, originEcef_.y, originEcef_.z, 1.0};
}

}  // namespace tinsmith::encode
