#include "server/http/route.hpp"

namespace tinsmith::server {

namespace {

/// z, x, y from three segments, the last one ending in `suffix`: a
/// RouteError unless each is a plain decimal integer below 2^32.
std::variant<Route, RouteError> parseTileSegments(Route route, const std::string& zText,
                                                  const std::string& xText,
                                                  const std::string& yFile,
                                                  std::string_view suffix,
                                                  bool geographic = false) {
  if (!yFile.ends_with(suffix)) return RouteError{"y", "the name must end in " + std::string(suffix)};
  const std::string_view yText = std::string_view(yFile).substr(0, yFile.size() - suffix.size());
  constexpr unsigned long long kMax = 0xffffffffULL;
  const auto z = parseBoundedUnsigned(zText, kMax);
  if (!z) return RouteError{"z", "z must be a non-negative integer below 2^32"};
  const auto x = parseBoundedUnsigned(xText, kMax);
  if (!x) return RouteError{"x", "x must be a non-negative integer below 2^32"};
  const auto y = parseBoundedUnsigned(yText, kMax);
  if (!y) return RouteError{"y", "y must be a non-negative integer below 2^32"};
  // The geographic grid has twice the columns (two tiles at level 0).
  if (*z > static_cast<unsigned long long>(kMaxZoom) || *x >> (*z + (geographic ? 1 : 0)) != 0 ||
      *y >> *z != 0) {
    route.outsidePyramid = true;
    return route;
  }
  route.tile = {static_cast<int>(*z), static_cast<std::uint32_t>(*x), static_cast<std::uint32_t>(*y)};
  return route;
}

}  // namespace

std::string_view routeName(RouteKind kind) {
  switch (kind) {
    case RouteKind::Index: return "index";
    case RouteKind::Health: return "health";
    case RouteKind::Metrics: return "metrics";
    case RouteKind::Tilesets: return "tilesets";
    case RouteKind::TilesetJson: return "tileset_json";
    case RouteKind::ExternalTileset: return "external_tileset";
    case RouteKind::Tile: return "tile";
    case RouteKind::TerrainLayer: return "terrain_layer";
    case RouteKind::TerrainTile: return "terrain_tile";
    case RouteKind::Elevation: return "elevation";
    case RouteKind::Profile: return "profile";
    case RouteKind::Lines: return "lines";
    case RouteKind::ThreePage: return "three_page";
    case RouteKind::ViewerAsset: return "viewer_asset";
    case RouteKind::Unknown: return "unknown";
  }
  return "unknown";
}

bool routeAllowsPost(RouteKind kind) {
  return kind == RouteKind::Elevation || kind == RouteKind::Profile;
}

bool isValidTilesetId(std::string_view id) {
  if (id.empty() || id.size() > 64 || id.front() == '.') return false;
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-' || c == '.';
    if (!ok) return false;
  }
  return true;
}

std::variant<Route, RouteError> matchRoute(const RequestTarget& target) {
  const auto& s = target.segments;
  Route route;
  if (target.trailingSlash) return route;  // no route ends in '/'
  if (s.empty()) {
    route.kind = RouteKind::Index;
    return route;
  }
  if (s.size() == 1) {
    if (s[0] == "health") route.kind = RouteKind::Health;
    if (s[0] == "metrics") route.kind = RouteKind::Metrics;
    if (s[0] == "tilesets") route.kind = RouteKind::Tilesets;
    if (s[0] == "three") route.kind = RouteKind::ThreePage;
    return route;
  }
  if (s[0] == "viewer") {
    route.kind = RouteKind::ViewerAsset;
    for (const auto& segment : s) route.asset += (route.asset.empty() ? "" : "/") + segment;
    return route;
  }
  if (s[0] != "tilesets" || !isValidTilesetId(s[1])) return route;
  route.tileset = s[1];
  if (s.size() == 3) {
    if (s[2] == "tileset.json") route.kind = RouteKind::TilesetJson;
    if (s[2] == "elevation") route.kind = RouteKind::Elevation;
    if (s[2] == "profile") route.kind = RouteKind::Profile;
    if (s[2] == "lines.geojson") route.kind = RouteKind::Lines;
    return route;
  }
  if (s.size() == 4 && s[2] == "terrain" && s[3] == "layer.json") {
    route.kind = RouteKind::TerrainLayer;
    return route;
  }
  if (s.size() == 6 && s[2] == "terrain") {
    route.kind = RouteKind::TerrainTile;
    return parseTileSegments(std::move(route), s[3], s[4], s[5], ".terrain", true);
  }
  if (s.size() == 6 && (s[2] == "tiles" || s[2] == "tilesets")) {
    const bool tile = s[2] == "tiles";
    route.kind = tile ? RouteKind::Tile : RouteKind::ExternalTileset;
    return parseTileSegments(std::move(route), s[3], s[4], s[5], tile ? ".glb" : ".json");
  }
  return route;
}

}  // namespace tinsmith::server
