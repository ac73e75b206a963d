// Project coordinates → WGS84 geodetic (EPSG:4979: lon, lat in degrees,
// ellipsoidal height in metres) through PROJ, for tile content.
//
// Heights: by default the TIN's z is taken as height above the ellipsoid
// (a projected CRS such as EPSG:26912 carries no vertical datum to convert
// from). With a geoid ("egm96"), z is an EGM96 orthometric height and PROJ's
// egm96_15.gtx grid (Debian's proj-data, offline) adds the geoid undulation.
// A compound CRS with a vertical datum ("EPSG:26912+5703", NAVD88 height)
// is converted by PROJ when the grids it needs are installed; when they are
// not, the constructor throws, naming them (PROJ itself would silently leave
// the heights unconverted). Debian bookworm's proj-data has EGM96's grid but
// none of NAVD88's.
// Thread-safe: each thread gets its own PROJ transformation.
#pragma once

#include <memory>
#include <string>

#include "core/tiles/tile_content.hpp"

namespace tinsmith::ingest {

/// Throws inputError (naming `tinName` when given) when a TIN's CRS is
/// empty (built without --crs): tiles are placed on the globe through it.
void requireTinCrs(const std::string& crs, const std::string& tinName = {});

class ProjGeoReference : public tiles::GeoReference {
 public:
  /// `crs`: the TIN's CRS ("EPSG:n", "EPSG:h+v" or WKT); `geoid`: "" or
  /// "egm96". Throws inputError, with what to do, for an empty or unknown CRS
  /// and for heights PROJ cannot convert here (a grid missing: named);
  /// usageError for an unknown geoid or a geoid given with a compound CRS.
  ProjGeoReference(std::string crs, std::string geoid);
  ~ProjGeoReference() override;
  void toGeodetic(std::span<const Point3> in, std::span<encode::Geodetic> out) const override;
  [[nodiscard]] const std::string& crs() const { return crs_; }
  [[nodiscard]] const std::string& geoid() const { return geoid_; }

 private:
  struct Transform;
  [[nodiscard]] Transform& forThisThread() const;
  std::string crs_;
  std::string geoid_;
  std::string sourceDefinition_;
  std::uint64_t serial_ = 0;
};

}  // namespace tinsmith::ingest
