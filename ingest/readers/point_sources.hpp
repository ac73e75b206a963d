// Point files as sources read a chunk at a time (the TIN built by blocks,
// ingest/build/block_tin.hpp): XYZ/CSV text a chunk at a time, the rest —
// synthetic specs, OGR point files — whole, as one chunk.
#pragma once

#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "core/base/point.hpp"

namespace tinsmith::ingest {

/// A point source read in chunks: calls `sink` with each chunk, in order.
struct PointSource {
  std::string name;  ///< the file, in messages
  std::function<void(const std::function<void(std::span<const Point3>)>& sink)> read;
};

/// Whether `path` is read as a DEM raster, every valid cell a point at its
/// centre (by extension: .tif .tiff .vrt .img .asc .hgt .dem .bil .exr).
bool isRasterPointFile(const std::filesystem::path& path);

/// A points file that is not XYZ/CSV text, read whole: a DEM raster, a
/// synthetic spec (readers/synthetic_reader.hpp) or an OGR file with 3D
/// points. Throws inputError naming the file when its points have no z.
std::vector<Point3> readNonTextPoints(const std::string& file);

/// The files as sources: text parsed on `threads` (0: every core) a chunk
/// of 8 MB at a time, rasters read in strips of about 4 M cells.
std::vector<PointSource> pointSources(const std::vector<std::string>& files, unsigned threads);

}  // namespace tinsmith::ingest
