// Earth frames for tile content (GeographicLib, WGS84): geodetic ↔ ECEF, a
// local east-north-up frame, and the root-node matrix glTF content needs in
// 3D Tiles. Accuracy: GeographicLib's, nanometres.
//
// 3D Tiles 1.1 turns glTF's y-up into the tileset's z-up by rotating +90°
// about x: (x, y, z) ↦ (x, −z, y). Tile content here is written z-up (ECEF or
// ENU axes, relative to a centre), so the root node carries the inverse turn
// and the centre: node matrix M = T⁻¹ · translate(centre), and then
// T · M · p = p + centre in the tileset's frame.
#pragma once

#include <array>

#include "core/base/point.hpp"

namespace tinsmith::encode {

/// A WGS84 position: longitude and latitude in degrees, height in metres above
/// the ellipsoid.
struct Geodetic {
  double lon = 0.0;
  double lat = 0.0;
  double height = 0.0;
};

/// ECEF metres of a geodetic position (GeographicLib::Geocentric::WGS84()).
/// Throws inputError for a non-finite value or a latitude outside [−90°, 90°]
/// (as do EnuFrame's constructor and fromGeodetic).
Point3 geodeticToEcef(const Geodetic& g);
/// The geodetic position of an ECEF point. Throws inputError if not finite.
Geodetic ecefToGeodetic(const Point3& ecef);

/// A column-major 4×4 matrix, as glTF and 3D Tiles store them.
using Matrix4 = std::array<double, 16>;

/// The glTF root-node matrix for z-up content whose positions are relative to
/// `centre` (see the file comment): T⁻¹ · translate(centre).
Matrix4 zUpContentRootMatrix(const Point3& centre);

/// The east-north-up frame at a geodetic origin (GeographicLib::LocalCartesian).
class EnuFrame {
 public:
  explicit EnuFrame(const Geodetic& origin);
  /// ENU metres of a geodetic position.
  [[nodiscard]] Point3 fromGeodetic(const Geodetic& g) const;
  /// ENU → ECEF as a column-major matrix (a tileset root `transform`).
  [[nodiscard]] Matrix4 toEcefMatrix() const;
  [[nodiscard]] const Geodetic& origin() const { return origin_; }

 private:
  Geodetic origin_;
  Point3 originEcef_;
  std::array<double, 9> rotation_{};  // row-major ENU → ECEF (columns e, n, u)
};

}  // namespace tinsmith::encode
