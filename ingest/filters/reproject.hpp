// filters.reproject: every layer into the project CRS.
//
// x, y go through PROJ (OGRCoordinateTransformation) with the traditional GIS
// axis order (x = easting/longitude, y = northing/latitude) on both sides, so
// EPSG:4326 data given as lon, lat and CRSs whose official order is
// northing-first (e.g. NZTM, EPSG:2193/3793) behave alike. z is left as it
// is: vertical datums are not changed.
//
// Throws tinsmith::Error (Input) naming the layer (and the feature where a
// point cannot be transformed): a layer without a CRS and without a `crs`
// override, a CRS PROJ does not know, a point outside the CRS's domain.
#pragma once

#include <string>
#include <vector>

#include "ingest/base/progress.hpp"
#include "ingest/readers/ingested_layer.hpp"

namespace tinsmith::ingest {

/// A reusable x, y transformation between two CRSs ("EPSG:n" or WKT).
class CrsTransform {
 public:
  /// `where` names the layer in errors.
  CrsTransform(const std::string& source, const std::string& target, const SourceLocation& where);
  ~CrsTransform();
  CrsTransform(const CrsTransform&) = delete;
  CrsTransform& operator=(const CrsTransform&) = delete;

  /// True when source and target are the same CRS: transform() does nothing.
  [[nodiscard]] bool identity() const { return transform_ == nullptr; }

  /// Transforms x, y of `points` in place; on failure returns the index of the
  /// first point that failed (left untransformed, as are the ones after it),
  /// else -1.
  std::int64_t transform(Point3* points, std::size_t count) const;

 private:
  void* transform_ = nullptr;  // OGRCoordinateTransformation
};

/// Moves `layer` into `targetCrs` (layer.crs becomes targetCrs).
void reprojectLayer(IngestedLayer& layer, const std::string& targetCrs,
                    const Progress* progress = nullptr);

}  // namespace tinsmith::ingest
