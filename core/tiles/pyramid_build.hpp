// Walks the pyramid from a root tile zoom by zoom: the tiles of a zoom are
// built on worker threads (each a pure function of its id), handed to the
// caller in (y, x) order on the calling thread, and their errors decide
// the next zoom's tiles (the four children of a refined tile, those that hold
// part of the TIN). Tiles the caller already has (a resumed run) are not
// rebuilt: their records stand in.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "core/tiles/tile_content.hpp"
#include "core/tiles/tile_mosaic.hpp"
#include "core/tiles/tiler.hpp"

namespace tinsmith::tiles {

struct PyramidCallbacks {
  /// The record of a tile the store already holds, or nullopt.
  std::function<std::optional<TileRecord>(const TileId&)> existing;
  /// A finished tile, a zoom's in (y, x) order (zoom by zoom, but the
  /// tiles above a mosaic zoom after it: buildPyramid); may throw (the walk
  /// stops).
  std::function<void(const TileContent&)> emit;
  /// Progress within a zoom: done of total tiles.
  std::function<void(int z, std::size_t done, std::size_t total)> progress;
  /// Set: the tiles above the tiler's mosaic zoom K are not built (a shard's
  /// merge builds them from every zoom-K surface: buildMosaicTop), and each
  /// zoom-K surface the walk builds, empty ones too, is handed here (on a
  /// worker thread) — those of a root at zoom K, or of all zoom K under
  /// 0/0/0. Not called for the tiles the caller already has (`existing`).
  std::function<void(const TileSurface&)> mosaicSurface;
};

struct PyramidSummary {
  std::vector<TileRecord> records;  ///< every tile of the (sub)pyramid, in (z, y, x) order
  std::size_t built = 0, reused = 0;
};

/// The skirt depth of a tile: twice its error, at least its zoom's tolerance.
double skirtDepth(const Tiler& tiler, const TileId& id, double error);

/// Throws usageError unless `root` is a tile of the pyramid: inside its
/// grid, and every ancestor refines (the ancestors are built and encoded with
/// `content`, not emitted, to see: a tile refines on its declared error). A
/// caller checks this before it touches any output.
void requireInPyramid(const Tiler& tiler, const ContentOptions& content, const TileId& root);
/// Why `root`, inside the grid, is not in the pyramid (an ancestor holds no
/// terrain or meets the tolerance), or nullopt when it is.
std::optional<std::string> whyNotInPyramid(const Tiler& tiler, const ContentOptions& content,
                                           const TileId& root);

/// Builds the pyramid under `root` (the whole pyramid for 0/0/0), which
/// must be a tile of the pyramid (requireInPyramid; only its grid is checked
/// here). Tiles at `untilZoom` and below are left out (the walk stops above
/// them). Under a tiler whose mosaic zoom K is above the root (which must
/// then be 0/0/0; usageError for another), zoom K and below come first,
/// from the TIN, then the tiles above K, fitted to the mosaic of every
/// zoom-K tile (tile_mosaic.hpp; those the walk did not build, as it stops
/// above K or the caller has them, are built for it) by a Tiler of the same
/// pyramid, each declaring its error against the mosaic plus the largest of
/// its zoom-K tiles'. The records are in (z, y, x) order all the same.
/// With callbacks.mosaicSurface, 0/0/0 stands for zoom K and below only.
PyramidSummary buildPyramid(const Tiler& tiler, const ContentOptions& content, const TileId& root,
                            int threads, const PyramidCallbacks& callbacks,
                            int untilZoom = 1 << 20);

/// How a walk encodes a non-empty tile surface (thread-safe).
using TileEncoder = std::function<TileContent(const TileSurface&)>;
/// The walk with another encoding (Cesium terrain: terrain_content.hpp).
PyramidSummary buildPyramid(const Tiler& tiler, const TileEncoder& encode, const TileId& root,
                            int threads, const PyramidCallbacks& callbacks,
                            int untilZoom = 1 << 20);

/// The tiles above frame.mosaicZoom K (≥ 1), as buildPyramid builds them
/// for a whole run, from `zoomK`: every zoom-K tile's surface, row by row
/// (4^K of them, empty where a tile holds no terrain) — what a sharded job's
/// shards handed over. The same bytes as the run's when the frame is its
/// Tiler's (frameOf) or what its build record names. internalError when a
/// surface is out of its place.
PyramidSummary buildMosaicTop(const PyramidFrame& frame, std::vector<TileSurface> zoomK,
                              const ContentOptions& content, int threads,
                              const PyramidCallbacks& callbacks);

}  // namespace tinsmith::tiles
