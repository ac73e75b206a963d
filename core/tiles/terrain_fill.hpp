// What a Cesium terrain tile holds where the TIN does not reach. A client's
// globe has no holes — every tile covers its whole rectangle — so outside
// the TIN a tile is the WGS84 ellipsoid (height 0, what CesiumJS draws with
// no terrain at all), and the TIN's edge stands on it as a vertical wall:
// the data ends there, visibly, and nothing is made up beyond it.
//
// The fill is the constrained Delaunay triangulation of the tile's rectangle
// less the surface's footprint (its boundary edges are the constraints), with
// a regular grid of `segments` × `segments` cells so that no chord sags far
// below the curved ellipsoid. Crack-free as the tiler's sides are: a side's
// fill vertices are the grid's points on it, computed from the side's own
// coordinates, outside the parts of it the surface covers (which both tiles
// sharing the side see the same, bit for bit).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/tiles/pyramid.hpp"
#include "core/tiles/tiler.hpp"

namespace tinsmith::tiles {

struct TerrainFill {
  std::vector<Point3> vertices;  ///< x, y in the surface's frame; z = 0
  /// Counter-clockwise. Numbering for both: i < surface.vertices.size() is
  /// the surface's vertex i, above it fill vertex i − surface.vertices.size().
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// Two per boundary edge of the surface inside the rectangle, from the
  /// edge down to the fill's copy of it, facing away from the surface.
  std::vector<std::array<std::uint32_t, 3>> walls;
};

/// The fill of `rect` outside `surface` (which may be empty: the whole
/// rectangle). `segments` ≥ 1 cells a side. Empty when the surface covers
/// the rectangle. Throws internalError when the surface's boundary does
/// not close.
TerrainFill fillOutsideSurface(const TileSurface& surface, const Rect& rect, int segments);

/// The grid a tile of `level` needs: the power of two of cells a side for
/// which a cell's triangles sag below the ellipsoid by at most a quarter of
/// CesiumJS's error for the level (a tile is 180° / 2^level a side).
int fillSegmentsForLevel(int level);

}  // namespace tinsmith::tiles
