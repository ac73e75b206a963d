// readers.raster / writers.raster: height grids in GeoTIFF (any GDAL raster on
// read) and OpenEXR, and the grid → points conversion for `dem` layers.
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
#include <cstdint>
#include <filesystem>
#include <optional>
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
  [[nodiscard]] Point2 cellCentre(int col, int row) const;
};

struct RasterReadOptions {
  int band = 1;                  ///< 1-based band (GDAL rasters)
  std::optional<double> nodata;  ///< overrides the file's own nodata value
};

/// Reads band `band` of any GDAL raster, or an EXR heightmap (by extension
/// .exr). Nodata cells (the file's or the override) become NaN.
/// Throws tinsmith::Error (Input) naming the file: missing, unreadable, no
/// such band, no georeferencing (a raster without a geotransform).
HeightGrid readHeightGrid(const std::filesystem::path& path, const RasterReadOptions& options = {});

/// Writes a GeoTIFF (Float32, deflate, nodata = NaN, tiled when large).
/// Writes to a temporary name and renames, so a failed write leaves no file.
/// Throws tinsmith::Error (Io).
void writeGeoTiff(const HeightGrid& grid, const std::filesystem::path& path);

/// Writes an OpenEXR heightmap with the attributes above (ZIP compression),
/// atomically like writeGeoTiff. Throws tinsmith::Error (Io).
void writeExr(const HeightGrid& grid, const std::filesystem::path& path);

/// Reads an EXR heightmap written by writeExr (or any single-channel float
/// EXR; georeferencing defaults to the identity with y down when absent).
HeightGrid readExr(const std::filesystem::path& path);

/// The grid's valid cells as points at cell centres (row-major order), and in
/// `cellIds` (if given) each point's row * width + col.
std::vector<Point3> gridToPoints(const HeightGrid& grid,
                                 std::vector<std::int64_t>* cellIds = nullptr);

}  // namespace tinsmith::ingest
