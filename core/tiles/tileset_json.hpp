// The 3D Tiles 1.1 scheme for a quadtree pyramid: tileset.json (and external
// tilesets for large pyramids) from the tiles' records. REPLACE refinement;
// `region` bounding volumes (or `box` in the local frame) grown to contain
// their children; each tile's geometricError is its measured error, raised to
// its children's where one of them measured more (so errors never grow down
// the tree and stay bounds); the tileset's error is twice the root's, at
// least the root's horizontal diagonal (metres).
//
// Content keys: "tiles/{z}/{x}/{y}.glb". External tilesets
// "tilesets/{z}/{x}/{y}.json" root the subtrees at zooms that are multiples
// of `externalEvery` once the pyramid has more than `maxTilesPerFile` tiles.
#pragma once

#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/tiles/tile_content.hpp"

namespace tinsmith::tiles {

struct TilesetOptions {
  std::size_t maxTilesPerFile = 4000;
  int externalEvery = 4;
  std::string generator = "tinsmith";
  /// Stored in the root tileset's `extras` (JSON object text), e.g. the CRS
  /// and tolerance; empty for none.
  std::string extras;
};

/// The key of a tile's content.
std::string tileContentKey(const TileId& id);

/// (key, JSON text) for "tileset.json" and every external tileset, in key
/// order. Throws internalError when the records do not form a tree under one
/// root (a tile whose parent is missing).
std::vector<std::pair<std::string, std::string>> tilesetFiles(std::span<const TileRecord> records,
                                                              const TilesetOptions& options);

}  // namespace tinsmith::tiles
