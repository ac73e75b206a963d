// A Cesium terrain tile (quantized-mesh-1.0, core/encode/quantized_mesh.hpp)
// from a tile surface of the geographic working frame (terrain_tiling.hpp):
// the surface, the fill outside it (terrain_fill.hpp), quantized over the
// tile's rectangle, with the tile's record — what layer.json, resume and the
// summary need of it — in the metadata extension as {"tinsmith": {...}}
// (recordToJson), so a store's terrain tiles describe themselves as its
// .glb tiles do.
//
// The record's error is measured as a 3D Tiles tile's is (tile_content.hpp):
// per triangle of the surface its vertical error measured before encoding,
// plus the farthest quantization moved one of its corners (to 0..32767
// across the tile and across its heights), plus its chord's sag below the
// ellipsoid; the fill's triangles count their sag alone (the fill is the
// ellipsoid); the walls count nothing (they stand where the data ends). A
// client draws the tile as it is for its level only when this is within
// CesiumJS's error for the level (cesiumLevelMaximumGeometricError).
#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "core/tiles/pyramid.hpp"
#include "core/tiles/terrain_lines.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tiler.hpp"

namespace tinsmith::tiles {

struct TerrainTileOptions {
  double west = -180.0;  ///< the working frame's (GeographicTin::west)
  /// Closed lake shores in the working frame: the water mask (none: land).
  const std::vector<TerrainLine>* lakes = nullptr;
};

/// Encodes pyramid tile `id` (a tile of the grid: geographicTileOf) of
/// `geometry` (geographicPyramid) from its surface, which may be empty (the
/// tile is then all fill). Extensions: vertex normals, the water mask (256 ×
/// 256 from the lakes, or one byte when the tile is all land or all water),
/// metadata (the record, naming the grid tile). The content's record names
/// the pyramid tile `id`.
TileContent encodeTerrainTile(const TileSurface& surface, const TileId& id,
                              const PyramidGeometry& geometry, const TerrainTileOptions& options);

/// The record in a terrain tile's metadata, its id the grid tile (TMS); nullopt
/// for bytes that are no quantized-mesh tile with a record.
std::optional<TileRecord> recordFromTerrainTile(std::string_view bytes);

/// The water mask of a rectangle of the working frame: 256 × 256 bytes from
/// its north-west corner row by row, 255 where a cell's centre is inside a
/// lake (even–odd over the shores), else 0; one byte when every cell is the
/// same.
std::vector<std::uint8_t> waterMask(const Rect& rect, const std::vector<TerrainLine>& lakes);

}  // namespace tinsmith::tiles
