// One tile of a finished store, built again from what the store carries: its
// TIN (tinsmith/terrain.tin) and its build record (tinsmith/build.json: the
// tiling options and the pyramid). Every tile is a pure function of the TIN,
// the options and its id (DESIGN.md "Tiles"), so a tile built here has the
// bytes `tinsmith tile` wrote, or would have written, for that id. The
// server's --on-demand builds the tiles a store lacks with it.
//
// The tileset.json cannot be made this way, tile by tile: a tile's declared
// geometricError is the largest measured error in its subtree, its bounding
// volume grows to contain its descendants', and whether it has children at
// all depends on its own measured error, so the tree needs every tile's
// record. A store whose tiles are built on demand keeps the tileset files
// written from a whole run (`tinsmith tile --keep-until-zoom`).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/tiles/pyramid.hpp"
#include "core/tiles/tile_content.hpp"

namespace tinsmith::ingest {

class TileRebuilder {
 public:
  /// `build` and `tin` are the store's tinsmith/build.json and
  /// tinsmith/terrain.tin; `store` names it in messages. Plans the pyramid
  /// (the finest fit: seconds on a large TIN). Throws inputError when the
  /// record is not one this version writes, the TIN is not the one it names
  /// (CRC), or the pyramid planned again differs from the recorded one.
  TileRebuilder(std::string_view build, std::string_view tin, const std::string& store);
  ~TileRebuilder();

  /// The tile's content, or nullopt when it holds none of the TIN. A zoom's
  /// fit is made by the first tile of the zoom and kept. Thread-safe.
  /// Throws usageError for an id outside the pyramid, inputError for one
  /// above the mosaic zoom (fitted to the mosaic of that zoom's tiles: a
  /// store holds every such tile).
  [[nodiscard]] std::optional<tiles::TileContent> build(const tiles::TileId& id) const;

  [[nodiscard]] int maxZoom() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tinsmith::ingest
