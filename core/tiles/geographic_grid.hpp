// The geographic tiling of Cesium terrain (quantized-mesh-1.0's default: the
// TMS layout on EPSG:4326): level 0 is two tiles, (0, 0, 0) from 180° W to
// Greenwich and (0, 1, 0) from Greenwich to 180° E, each from pole to pole;
// level z has 2^(z+1) columns west to east and 2^z rows south to north, each
// tile 180° / 2^z a side in degrees. Bounds are computed from the integers
// alone, so tiles sharing a side or a corner get the same doubles for it.
#pragma once

#include <cstdint>
#include <optional>

#include "core/tiles/pyramid.hpp"

namespace tinsmith::tiles {

/// A longitude/latitude rectangle, degrees (west < east: none crosses 180°).
struct GeoRect {
  double west = 0, south = 0, east = 0, north = 0;
};

/// Whether (z, x, y) is a tile of the grid (z in 0..30, x < 2^(z+1), y < 2^z).
bool isGeographicTile(const TileId& id);

/// The tile's bounds. Throws usageError for a tile outside the grid.
GeoRect geographicTileBounds(const TileId& id);

/// The error CesiumJS allows a terrain tile of `level` on the WGS84 globe
/// (TerrainProvider.getEstimatedLevelZeroGeometricErrorForAHeightmap with a
/// 65-sample tile and two level-0 tiles, halved each level): 2π·a / 4 /
/// (65 · 2) / 2^level, 77 067.34 m at level 0. A tile must be within it for
/// CesiumJS to pick levels as it means to.
double cesiumLevelMaximumGeometricError(int level);

/// The tiles of one level that meet a rectangle (closed), as layer.json's
/// "available" ranges give them: columns startX..endX, rows startY..endY,
/// inclusive. nullopt when the rectangle is empty or off the globe.
struct TileRange {
  std::uint32_t startX = 0, startY = 0, endX = 0, endY = 0;
};
std::optional<TileRange> geographicTilesCovering(const GeoRect& rect, int level);

}  // namespace tinsmith::tiles
