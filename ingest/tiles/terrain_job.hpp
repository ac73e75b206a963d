// Cesium terrain in a tile store (`tinsmith tile --scheme quantized-mesh` or
// `both`): the TIN in the geographic working frame (core/tiles/terrain_tiling.hpp)
// walked by the tiler down to the first level whose CesiumJS error is within
// the tolerance, each tile encoded as quantized-mesh-1.0
// (core/tiles/terrain_content.hpp), under the keys
//   terrain/layer.json                  the layer: available ranges per level,
//                                       bounds, extensions, attribution
//   terrain/{level}/{x}/{y}.terrain     TMS numbering (y from the south)
// Both level-0 tiles are always there (CesiumJS starts from them; one
// without terrain is all ellipsoid). Tiles at levels 0, 10, 20 also carry in
// their metadata the availability of the ten levels below them in their own
// subtree, as the metadata extension defines it.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/tiles/terrain_tiling.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tin/tin_data.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::ingest {

inline constexpr const char* kTerrainLayerKey = "terrain/layer.json";

/// "terrain/{level}/{x}/{y}.terrain" of a grid tile (TMS numbering).
std::string terrainTileKey(const tiles::TileId& gridTile);
/// The grid tile of such a key; nullopt for any other key.
std::optional<tiles::TileId> gridTileOfKey(std::string_view key);

/// Tiles `frame` (the TIN in the geographic working frame) as Cesium terrain into `stage`, the
/// tiles first and layer.json last. With `resume`, tiles already in `stage`
/// or in `previous` (a finished store of the same build) are taken as they
/// are. Returns the summary and, in `keys`, what it wrote in canonical order.
TerrainSummary tileTerrain(const tiles::GeographicTin& frame, const TileJobOptions& options,
                           store::TileStore& stage, const store::TileStore* previous,
                           std::vector<std::string>& keys, const Progress* progress);

/// A stored terrain tile: its grid tile, its record, its size in bytes.
struct TerrainTileEntry {
  tiles::TileId grid;
  tiles::TileRecord record;
  std::size_t bytes = 0;
};

/// Per level: tiles, triangles, bytes, the largest error and the tiles over
/// CesiumJS's error for the level (missed). Leaves finestLevel, built and
/// reused at 0.
TerrainSummary summarizeTerrain(const std::vector<TerrainTileEntry>& tiles);

/// The terrain a store holds, from its tiles' records (tinsmith info):
/// nullopt for a store with none; finestLevel is layer.json's maxzoom (the
/// deepest tile's level while it is missing). Throws inputError for a tile
/// without a record.
std::optional<TerrainSummary> describeTerrain(const store::TileStore& store);

/// The grid tiles a layer.json's "available" lists, per level: rows of
/// consecutive columns, rows with the same columns one above the other
/// joined. `tiles` in any order.
nlohmann::ordered_json availableRanges(std::vector<tiles::TileId> tiles, int levels);

}  // namespace tinsmith::ingest
