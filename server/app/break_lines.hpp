// The break lines of a tileset's TIN as GeoJSON (RFC 7946), for
// GET /tilesets/{id}/lines.geojson: the TIN's constrained edges, per input
// feature, chained into LineStrings — one Feature per chain, properties
// {"feature": its id in the TIN, "kind": "road" | "river" | "lake" |
// "contour" | "boundary" | …, "source": where it came from}.
//
// Coordinates are [lon, lat, h]: WGS84 degrees (rounded to 1e-8°, about a
// millimetre) and h the height above the WGS84 ellipsoid in metres (to the
// millimetre), as RFC 7946 § 4 has it — the TIN's z plus the geoid
// undulation when the store was built with a geoid, so the lines sit on the
// tiles' surface. Deterministic: features in id order, chains from their
// lowest free end (then cycles from their lowest vertex).
#pragma once

#include <nlohmann/json.hpp>

#include "server/app/tileset_catalog.hpp"

namespace tinsmith::server {

/// Throws what Tileset::surface() and Tileset::toGeodetic() throw.
nlohmann::ordered_json breakLinesGeoJson(const Tileset& tileset);

}  // namespace tinsmith::server
