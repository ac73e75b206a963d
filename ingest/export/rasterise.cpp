#include "ingest/export/rasterise.hpp"

#include <cmath>

#include "core/base/error.hpp"
#include "core/surface/surface.hpp"
#include "ingest/export/raster_writer.hpp"

namespace tinsmith::ingest {

HeightGrid rasteriseTin(const TinData& tin, double cell, std::size_t maxCells) {
  if (!(cell > 0) || !std::isfinite(cell)) throw usageError("the cell size must be a positive number of metres");
  if (tin.triangles.empty() || tin.vertices.empty())
    throw geometryError("the TIN has no triangles to rasterise");
  double minX = tin.vertices[0].x, maxX = minX, minY = tin.vertices[0].y, maxY = minY;
  for (const auto& v : tin.vertices) {
    minX = std::min(minX, v.x);
    maxX = std::max(maxX, v.x);
    minY = std::min(minY, v.y);
    maxY = std::max(maxY, v.y);
  }
  const double cols = std::max(1.0, std::ceil((maxX - minX) / cell));
  const double rows = std::max(1.0, std::ceil((maxY - minY) / cell));
  if (cols * rows > static_cast<double>(maxCells))
    throw usageError("a cell of " + std::to_string(cell) + " m makes " +
                         std::to_string(static_cast<long long>(cols)) + " × " +
                         std::to_string(static_cast<long long>(rows)) + " cells, too many",
                     "choose a larger --cell");
  HeightGrid grid;
  grid.width = static_cast<int>(cols);
  grid.height = static_cast<int>(rows);
  grid.geotransform = {minX, cell, 0.0, maxY, 0.0, -cell};
  grid.crs = tin.crs;
  const Surface surface(tin);
  const SampleGrid sg{minX + 0.5 * cell, maxY - 0.5 * cell, cell, -cell,
                      static_cast<std::size_t>(grid.width), static_cast<std::size_t>(grid.height)};
  const std::vector<double> z = surface.zGrid(sg);
  grid.z.resize(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) grid.z[i] = static_cast<float>(z[i]);
  return grid;
}

void writeHeightmap(const TinData& tin, double cell, const std::string& format,
                    const std::filesystem::path& path) {
  const HeightGrid grid = rasteriseTin(tin, cell);
  if (format == "exr")
    writeExr(grid, path);
  else if (format == "tif")
    writeGeoTiff(grid, path);
  else
    throw usageError("unknown heightmap format '" + format + "'", "use exr or tif");
}

}  // namespace tinsmith::ingest
