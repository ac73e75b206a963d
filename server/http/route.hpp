// The server's routes (DESIGN.md "Server") as typed values: a decoded
// request-target becomes a Route or a RouteError, never a path. Tile and
// external-tileset coordinates are parsed as integers here; whether they lie
// in a tileset's pyramid is the catalog's question (404 there).
//
//   /                                         Index
//   /health  /metrics  /tilesets              Health, Metrics, Tilesets
//   /tilesets/{id}/tileset.json               TilesetJson
//   /tilesets/{id}/tilesets/{z}/{x}/{y}.json  ExternalTileset
//   /tilesets/{id}/tiles/{z}/{x}/{y}.glb      Tile
//   /tilesets/{id}/terrain/layer.json         TerrainLayer (Cesium terrain)
//   /tilesets/{id}/terrain/{z}/{x}/{y}.terrain  TerrainTile (TMS: 2^(z+1) columns)
//   /tilesets/{id}/elevation                  Elevation
//   /tilesets/{id}/profile                    Profile
//   /tilesets/{id}/lines.geojson              Lines
//   /three                                    ThreePage (the three.js viewer)
//   /viewer/…                                 ViewerAsset (a file of the viewer)
#pragma once

#include <string>
#include <string_view>
#include <variant>

#include "core/tiles/pyramid.hpp"
#include "server/http/request_target.hpp"

namespace tinsmith::server {

enum class RouteKind {
  Index,
  Health,
  Metrics,
  Tilesets,
  TilesetJson,
  ExternalTileset,
  Tile,
  TerrainLayer,
  TerrainTile,
  Elevation,
  Profile,
  Lines,
  ThreePage,
  ViewerAsset,
  Unknown,  ///< no route (404); also the metrics label of malformed targets
};
inline constexpr int kRouteKinds = static_cast<int>(RouteKind::Unknown) + 1;

/// The metrics label: "index", "tile", …
std::string_view routeName(RouteKind kind);

/// Which methods a route answers; HEAD goes with GET, OPTIONS (CORS
/// preflight) with every route.
bool routeAllowsPost(RouteKind kind);

/// Deepest zoom a tile id may name (2^30 tiles a side fit x, y in uint32).
inline constexpr int kMaxZoom = 30;

struct Route {
  RouteKind kind = RouteKind::Unknown;
  std::string tileset;  ///< the id, for the per-tileset routes
  tiles::TileId tile;   ///< Tile, ExternalTileset and TerrainTile (a grid tile)
  /// z/x/y are integers but name no tile (z > kMaxZoom, x or y ≥ 2^z): a 404.
  bool outsidePyramid = false;
  /// ViewerAsset: the decoded segments joined by '/' ("viewer/lib/…"), a
  /// key for the viewer's table of files, never a file path.
  std::string asset;
};

/// A target that names a route shape with a bad part: 400 naming `parameter`.
struct RouteError {
  std::string parameter;  ///< "z", "x", "y"
  std::string message;
};

/// Whether `id` can name a tileset: 1-64 of [A-Za-z0-9_.-], not starting with '.'.
bool isValidTilesetId(std::string_view id);

/// Matches a decoded target against the routes. A segment that fits no route
/// gives RouteKind::Unknown; z, x, y that are not plain decimal integers
/// below 2^32 (a sign, a leading zero, letters, overflow) give a RouteError;
/// integers that name no tile set Route::outsidePyramid.
std::variant<Route, RouteError> matchRoute(const RequestTarget& target);

}  // namespace tinsmith::server
