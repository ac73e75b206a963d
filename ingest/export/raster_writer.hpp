// writers.raster: height grids as GeoTIFF or OpenEXR heightmaps (the EXR
// convention: ingest/base/height_grid.hpp), written to a unique temp file
// beside the target and renamed over it (AtomicPath), so a failed write leaves
// no file and two writers of one target do not collide.
#pragma once

#include <filesystem>

#include "ingest/base/height_grid.hpp"

namespace tinsmith::ingest {

/// Writes a GeoTIFF (Float32, deflate, nodata = NaN, tiled when large).
/// Writes to a temporary name and renames, so a failed write leaves no file.
/// Throws tinsmith::Error (Io).
void writeGeoTiff(const HeightGrid& grid, const std::filesystem::path& path);

/// Writes an OpenEXR heightmap with the attributes of height_grid.hpp (ZIP compression),
/// atomically like writeGeoTiff. Throws tinsmith::Error (Io).
void writeExr(const HeightGrid& grid, const std::filesystem::path& path);

}  // namespace tinsmith::ingest
