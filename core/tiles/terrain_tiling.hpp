// Cesium terrain (quantized-mesh-1.0 on the geographic grid of
// geographic_grid.hpp) cut by the tiler itself, so it keeps the tiler's
// guarantees: break lines exact, sides shared bit for bit, every tile's error
// measured. The TIN is re-expressed in a geographic working frame — x, y the
// longitude and latitude times kMetresPerDegree, z the height above the WGS84
// ellipsoid — where the grid's tiles are the squares of one pyramid
// (geographicPyramid): the square from (west, −90°) 360° a side, whose zoom
// z + 1 is the grid's level z (its south half; the north half is off the
// globe and holds nothing). Tile sides are then meridians and parallels, as
// a client's are, and the tiler's zoom tolerances are CesiumJS's level errors
// (both halve each level).
//
// The TIN's triangles are straight in the working frame between its vertices
// (exactly the TIN's vertices, so break lines stay where they are), not in
// the project CRS: the two differ by the projection's curvature across a
// triangle, under a millimetre for triangles of 100 m (the scale factor of a
// transverse Mercator changes by 1e-8 over 100 m near its central meridian).
#pragma once

#include <numbers>
#include <optional>

#include "core/tiles/pyramid.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tiler.hpp"
#include "core/tin/tin_data.hpp"

namespace tinsmith::tiles {

/// Metres per degree of the working frame: the equator's (π·a / 180 on
/// WGS84), so x, y are near metres for the tiler's margins and its chord-sag
/// estimates (an overestimate east–west away from the equator).
inline constexpr double kMetresPerDegree = std::numbers::pi * 6378137.0 / 180.0;

/// The working frame as a georeference: (x / k, y / k) degrees, z the
/// ellipsoidal height.
class GeographicFrame final : public GeoReference {
 public:
  void toGeodetic(std::span<const Point3> in, std::span<encode::Geodetic> out) const override;
};

struct GeographicTin {
  TinData tin;  ///< in the working frame (crs "tinsmith:geographic")
  /// The frame's west edge: −180°, or 0° for a TIN across the antimeridian,
  /// whose longitudes then run on past 180° (a tile's sides still never cross it).
  double west = -180.0;
};

/// The TIN in the working frame, positions through `project` (its CRS and
/// vertical datum to WGS84). Throws geometryError, naming the place, for a
/// triangle whose orientation the frame flips (a sliver below the
/// projection's rounding) or one that spans more than 180° of longitude
/// (a TIN around a pole).
GeographicTin toGeographicTin(const TinData& tin, const GeoReference& project);

/// The pyramid whose zoom z + 1 is the grid's level z (file comment).
PyramidGeometry geographicPyramid(double west);

/// The grid's tile (level z − 1) of a pyramid tile; nullopt for the root and
/// the rows north of the pole.
std::optional<TileId> geographicTileOf(const TileId& pyramidTile, double west);

/// The first level whose CesiumJS error (cesiumLevelMaximumGeometricError)
/// is at most `tolerance` metres. Throws usageError for a tolerance finer
/// than the deepest level the tiler can fit (28: 0.3 mm).
int terrainLevelFor(double tolerance);

/// The tiler's options for terrain down to `finestLevel` of the grid: the
/// fixed pyramid, its finest zoom finestLevel + 1 meeting that level's
/// error, the root (no tile of the grid) always refined into level 0, and
/// no zoom deeper unless `base` sets one.
TilerOptions terrainTilerOptions(TilerOptions base, double west, int finestLevel);

}  // namespace tinsmith::tiles
