// writers.heightmap: a TIN sampled onto a regular grid (the piecewise linear
// surface, core/surface) for `tinsmith export --format exr|tif --cell C`.
//
// The grid covers the TIN's x, y extent with square cells of `cell` metres,
// north-up: the top-left corner is (minX, maxY), the cell (col, row) is
// sampled at its centre (minX + (col + ½)·cell, maxY − (row + ½)·cell).
// Cells whose centre lies outside every triangle (outside a non-convex
// boundary, in a hole) are NaN = nodata. z is stored as 32-bit float.
#pragma once

#include <cstddef>
#include <filesystem>

#include "core/tin/tin_data.hpp"
#include "ingest/base/height_grid.hpp"

namespace tinsmith::ingest {

/// Throws usageError for a cell that is not positive or would make more than
/// `maxCells` cells, geometryError for a TIN without triangles.
HeightGrid rasteriseTin(const TinData& tin, double cell, std::size_t maxCells = 400'000'000);

/// rasteriseTin, then writeExr / writeGeoTiff by `format` ("exr" or "tif");
/// atomic like those writers.
void writeHeightmap(const TinData& tin, double cell, const std::string& format,
                    const std::filesystem::path& path);

}  // namespace tinsmith::ingest
