// A height grid in memory: what the raster readers make and the raster
// writers, the rasteriser and `tinsmith fit` take.
//
// Georeferencing in EXR files (tinsmith's convention, written and read here):
//   * channel "Z", 32-bit FLOAT, one sample per cell, NaN = nodata (on read,
//     a lone channel of any name, or "Y", is accepted too);
//   * attribute "geoTransform" (M33d): the affine map from cell corner
//     (col, row, 1) to CRS (x, y, 1), i.e. GDAL's geotransform gt as
//       | gt[1] gt[2] gt[0] |
//       | gt[4] gt[5] gt[3] |
//       |   0     0     1   |
//   * attribute "crs" (string): "EPSG:n" or WKT; absent when unknown.
// EXR data window = (0, 0) – (width-1, height-1); row 0 is the first (top,
// northern for a north-up grid) row, as in GeoTIFF.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "core/base/point.hpp"

namespace tinsmith::ingest {

/// A north-up (or any affine) height grid. Cell (col, row) covers the
/// parallelogram whose top-left corner is geotransform applied to (col, row);
/// its height applies at the cell centre (col + 0.5, row + 0.5).
struct HeightGrid {
  int width = 0;
  int height = 0;
  std::array<double, 6> geotransform{0.0, 1.0, 0.0, 0.0, 0.0, -1.0};  ///< GDAL order
  std::string crs;       ///< "EPSG:n" or WKT; empty when unknown
  std::vector<float> z;  ///< row-major, width * height; NaN = nodata

  [[nodiscard]] float at(int col, int row) const {
    return z[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
             static_cast<std::size_t>(col)];
  }
  /// CRS coordinates of the centre of cell (col, row).
  [[nodiscard]] Point2 cellCentre(int col, int row) const {
    const double c = col + 0.5;
    const double r = row + 0.5;
    const auto& g = geotransform;
    return {g[0] + c * g[1] + r * g[2], g[3] + c * g[4] + r * g[5]};
  }
};

}  // namespace tinsmith::ingest
