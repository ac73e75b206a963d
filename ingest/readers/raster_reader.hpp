// readers.raster: height grids from any GDAL raster or an OpenEXR heightmap
// (the EXR convention: ingest/base/height_grid.hpp), and the grid → points
// conversion for `dem` layers.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "core/base/point.hpp"
#include "ingest/base/height_grid.hpp"

namespace tinsmith::ingest {

struct RasterReadOptions {
  int band = 1;                  ///< 1-based band (GDAL rasters)
  std::optional<double> nodata;  ///< overrides the file's own nodata value
};

/// Reads band `band` of any GDAL raster, or an EXR heightmap (by extension
/// .exr). Nodata cells (the file's or the override) become NaN.
/// Throws tinsmith::Error (Input) naming the file: missing, unreadable, no
/// such band, no georeferencing (a raster without a geotransform).
HeightGrid readHeightGrid(const std::filesystem::path& path, const RasterReadOptions& options = {});

/// Reads the raster as readHeightGrid does, about `stripCells` cells (whole
/// rows, at least one) at a time: `strip`
/// gets the grid's frame (size, geotransform, CRS; no cells), the strip's
/// first row and its cells (NaN = nodata). An EXR heightmap comes whole, in
/// one strip.
void readHeightGridInStrips(const std::filesystem::path& path, const RasterReadOptions& options,
                            std::size_t stripCells,
                            const std::function<void(const HeightGrid& frame, int firstRow,
                                                     std::span<const float> z)>& strip);
/// A strip's valid cells as points at cell centres: gridToPoints's points of
/// those rows.
std::vector<Point3> stripToPoints(const HeightGrid& frame, int firstRow, std::span<const float> z);

/// Reads an EXR heightmap written by writeExr (or any single-channel float
/// EXR; georeferencing defaults to the identity with y down when absent).
HeightGrid readExr(const std::filesystem::path& path);

/// The grid's valid cells as points at cell centres (row-major order), and in
/// `cellIds` (if given) each point's row * width + col.
std::vector<Point3> gridToPoints(const HeightGrid& grid,
                                 std::vector<std::int64_t>* cellIds = nullptr);

}  // namespace tinsmith::ingest
