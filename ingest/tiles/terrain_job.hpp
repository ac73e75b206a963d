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
#include <string>
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

/// Tiles `frame` (the TIN in the geographic working frame) as Cesium terrain into `stage`, the
/// tiles first and layer.json last. With `resume`, tiles already in `stage`
/// or in `previous` (a finished store of the same build) are taken as they
/// are. Returns the summary and, in `keys`, what it wrote in canonical order.
TerrainSummary tileTerrain(const tiles::GeographicTin& frame,
                           const TileJobOptions& options, store::TileStore& stage,
                           const store::TileStore* previous, std::vector<std::string>& keys,
                           const Progress* progress);

/// The grid tiles a layer.json's "available" lists, per level: rows of
/// consecutive columns, rows with the same columns one above the other
/// joined. `tiles` in any order.
nlohmann::ordered_json availableRanges(std::vector<tiles::TileId> tiles, int levels);

}  // namespace tinsmith::ingest
