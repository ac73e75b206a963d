// The mosaic of one zoom's tile surfaces as a TIN: what the tiles above that
// zoom can be fitted to instead of the TIN itself (docs/benchmarks.md, issue
// 24's "the top from the subtrees' reports"). The tiles of a zoom share
// their sides' vertices bit for bit (tiler.hpp), so their surfaces join
// into one crack-free triangulation; its break lines are the tiles' line
// edges (rivers kept apart), its domain the tiles' own, whose boundary
// edges are the rings a Tiler finds in it.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "core/tiles/tiler.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::tiles {

struct TileMosaic {
  TinData tin;
  /// The largest TileSurface::error of the tiles (m): how far the mosaic is
  /// from the TIN they were built of, vertically.
  double maxError = 0.0;
};

/// The tiles' surfaces joined: vertices merged where x and y are the same
/// doubles (in the order first met), triangles in the tiles' order, and a
/// constrained edge for each held edge inside a tile that two of its
/// triangles share (feature 0 a break line, 1 a river): not the tile sides,
/// nor the rings, whose edges are the mosaic's boundary. A break line that
/// runs exactly along a tile side is left out with the side. `crs` is the
/// TIN's. Empty tiles are skipped. Throws internalError when two tiles give
/// a shared vertex different z (they are not the tiles of one Tiler's zoom)
/// or a tile lacks its flags or held edges.
TileMosaic mosaicOf(std::span<const TileSurface> tiles, const std::string& crs);

/// What a Tiler over the mosaic of a pyramid's zoom-K tiles needs of that
/// pyramid to build the tiles above K: a Tiler's (frameOf), or what a build
/// record names (a merge's, which has no TIN).
struct PyramidFrame {
  /// The tiling options: tolerance, maxTriangles, lambdaFactor and geo are
  /// read (the rest are a fixed pyramid's, set by mosaicTopOptions). An
  /// option that changes tiles goes into the build record too, which a
  /// merge makes this from (ingest/tiles/tile_job.cpp).
  TilerOptions options;
  PyramidGeometry geometry{{0, 0}, 1};
  int finestZoom = 0;
  int maxZoom = 0;
  int mosaicZoom = 0;  ///< K
  std::string crs;     ///< the TIN's
};
PyramidFrame frameOf(const Tiler& tiler);

/// The options of a Tiler over a mosaic that builds `frame`'s tiles above
/// zoom k: its pyramid, finest zoom, tolerances and budget, every tile above
/// k refined, and each tile's mosaicError E the largest of `errors` — the
/// errors of the mosaic's zoom-m tiles (m ≥ k), row by row — under it.
TilerOptions mosaicTopOptions(const PyramidFrame& frame, int k, int m, std::vector<double> errors);

}  // namespace tinsmith::tiles
