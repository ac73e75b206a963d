// Elevation and profile answers from a tileset's TIN (core/surface), as JSON.
// z is the TIN's barycentric z at the point — the same double `tinsmith
// query` prints. Coordinates are the project CRS (x, y, metres) or WGS84
// lon, lat in degrees (converted through PROJ as ingest does); distances
// along a profile are in the project CRS.
//
// Every function throws ParameterError for a bad or missing parameter (400
// naming it) and returns nullopt-like JSON null z for points off the TIN,
// except the single-point GET, which is a 404 there (see tile_service.cpp).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "server/app/tileset_catalog.hpp"
#include "server/http/request_target.hpp"

namespace tinsmith::server {

/// A request parameter that is missing or malformed: a 400 naming it.
struct ParameterError : std::runtime_error {
  ParameterError(std::string parameter, const std::string& message)
      : std::runtime_error(message), parameter(std::move(parameter)) {}
  std::string parameter;
};

/// At most this many points in one batch, samples in one profile.
inline constexpr std::size_t kMaxPoints = 10'000;

/// GET …/elevation?x=&y= or ?lon=&lat=: {"x","y"[,"lon","lat"],"z","slope",
/// "aspect","ellipsoidalHeight"}; z null (and nothing after it) off the TIN.
/// slope: of the TIN triangle under the point, degrees from level; aspect:
/// the way it faces (downhill), degrees clockwise from the project CRS's grid
/// north, null where level; ellipsoidalHeight: z as the tiles place it (plus
/// the store's geoid undulation, if any), metres above WGS84's ellipsoid.
nlohmann::ordered_json elevationAt(const Tileset& tileset, const RequestTarget& query);
/// POST …/elevation {"points": [[x, y], …], "crs": "project" | "lonlat"}:
/// {"crs", "points": [{"x","y","z",…}, …]}, each point as the GET answers it.
nlohmann::ordered_json elevationBatch(const Tileset& tileset, const std::string& body);
/// GET …/profile?line=x,y;x,y;…[&spacing=S] (or lonlat=lon,lat;…), or POST
/// {"line": [[x, y], …], "spacing": S, "crs": …}: samples at every multiple
/// of the spacing along the line and at its vertices, each {"distance",
/// "x", "y", "z"}; default spacing: the length / 256.
nlohmann::ordered_json profileAlong(const Tileset& tileset, const RequestTarget& query);
nlohmann::ordered_json profileBatch(const Tileset& tileset, const std::string& body);

}  // namespace tinsmith::server
