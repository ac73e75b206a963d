#include "core/tiles/tile_content.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/base/error.hpp"
#include "core/encode/mesh_buffers.hpp"
#include "core/tiles/lon_range.hpp"

namespace tinsmith::tiles {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

/// What a tile's rectangle is on the globe: the longitude of its centre, and
/// which pole its sides go around (+1 north, −1 south, 0 none; their
/// longitudes wind once around it).
struct BoundsOnGlobe {
  double centreLon = 0;
  int pole = 0;
};

BoundsOnGlobe boundsOnGlobe(const Rect& r, const GeoReference& geo) {
  constexpr int kPerSide = 16;
  std::vector<Point3> ring;
  ring.reserve(4 * kPerSide + 1);
  const Point2 corners[] = {{r.x0, r.y0}, {r.x1, r.y0}, {r.x1, r.y1}, {r.x0, r.y1}};
  for (int side = 0; side < 4; ++side) {
    const Point2 a = corners[side], b = corners[(side + 1) % 4];
    for (int k = 0; k < kPerSide; ++k) {
      const double t = static_cast<double>(k) / kPerSide;
      ring.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), 0.0});
    }
  }
  ring.push_back({0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1), 0.0});
  std::vector<encode::Geodetic> g(ring.size());
  geo.toGeodetic(ring, g);
  BoundsOnGlobe out;
  out.centreLon = g.back().lon * kDegree;
  double winding = 0, lat = 0;
  const std::size_t n = ring.size() - 1;
  for (std::size_t i = 0; i < n; ++i) {
    winding += wrapLongitude((g[(i + 1) % n].lon - g[i].lon) * kDegree);
    lat += g[i].lat;
  }
  if (std::abs(winding) > std::numbers::pi) out.pole = lat > 0 ? 1 : -1;
  return out;
}

}  // namespace

std::string recordToJson(const TileRecord& r) {
  nlohmann::ordered_json j;
  j["tile"] = {r.id.z, r.id.x, r.id.y};
  j["geometricError"] = r.error;
  if (r.local) {
    j["box"] = r.box;
  } else {
    j["region"] = r.region;
  }
  j["vertices"] = r.vertices;
  j["triangles"] = r.triangles;
  j["breakLineVertices"] = r.breakLineVertices;
  j["positionErrorBound"] = r.positionErrorBound;
  nlohmann::ordered_json root;
  root["tinsmith"] = j;
  return root.dump();
}

std::optional<TileRecord> recordFromExtras(std::string_view extras) {
  if (extras.empty()) return std::nullopt;
  const auto root = nlohmann::json::parse(extras, nullptr, false);
  if (root.is_discarded() || !root.is_object() || !root.contains("tinsmith")) return std::nullopt;
  const auto& j = root["tinsmith"];
  try {
    TileRecord r;
    const auto& t = j.at("tile");
    r.id = {t.at(0).get<int>(), t.at(1).get<std::uint32_t>(), t.at(2).get<std::uint32_t>()};
    r.error = j.at("geometricError").get<double>();
    if (j.contains("box")) {
      r.local = true;
      r.box = j["box"].get<std::array<double, 12>>();
    } else {
      r.region = j.at("region").get<std::array<double, 6>>();
    }
    r.vertices = j.value("vertices", std::size_t{0});
    r.triangles = j.value("triangles", std::size_t{0});
    r.breakLineVertices = j.value("breakLineVertices", std::size_t{0});
    r.positionErrorBound = j.value("positionErrorBound", 0.0);
    return r;
  } catch (const nlohmann::json::exception&) {
    return std::nullopt;
  }
}

std::optional<TileRecord> recordFromGlb(std::string_view glb) {
  try {
    return recordFromExtras(encode::glbAssetExtras(glb, "tile"));
  } catch (const Error&) {
    return std::nullopt;
  }
}

TileContent encodeTile(const TileSurface& tile, double skirtDepth, const ContentOptions& options) {
  if (tile.empty()) throw internalError("encodeTile: tile " + tile.id.name() + " is empty");
  if (!options.geo) throw internalError("encodeTile: no georeference");

  // Vertices: the surface's, then one below each side vertex that a skirt uses.
  std::vector<Point3> project = tile.vertices;
  const std::size_t top = project.size();
  std::vector<std::uint32_t> below(top, std::numeric_limits<std::uint32_t>::max());
  std::vector<std::array<std::uint32_t, 3>> triangles = tile.triangles;
  for (const auto& t : tile.triangles) {
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = t[i], b = t[(i + 1) % 3];
      // An edge with both ends on one side lies along it (the side is a
      // constraint through all its vertices), so the tile is on one side of it.
      if ((tile.flags[a] & tile.flags[b] & 15) == 0) continue;
      for (std::uint32_t v : {a, b}) {
        if (below[v] == std::numeric_limits<std::uint32_t>::max()) {
          below[v] = static_cast<std::uint32_t>(project.size());
          project.push_back(
              {tile.vertices[v].x, tile.vertices[v].y, tile.vertices[v].z - skirtDepth});
        }
      }
      // Interior on the left of a → b; the skirt faces outward.
      triangles.push_back({a, below[a], below[b]});
      triangles.push_back({a, below[b], b});
    }
  }

  std::vector<encode::Geodetic> geodetic(project.size());
  options.geo->toGeodetic(project, geodetic);
  TileRecord record;
  record.id = tile.id;
  record.error = tile.error;
  record.breakLineVertices = tile.breakLineVertices;
  record.vertices = project.size();
  record.triangles = triangles.size();

  std::vector<Point3> frame(project.size());
  if (options.frame == ContentFrame::Ecef) {
    for (std::size_t i = 0; i < project.size(); ++i) frame[i] = encode::geodeticToEcef(geodetic[i]);
    double s = HUGE_VAL, n = -HUGE_VAL, h0 = HUGE_VAL, h1 = -HUGE_VAL;
    std::vector<double> lons(geodetic.size());
    for (std::size_t i = 0; i < geodetic.size(); ++i) {
      const auto& g = geodetic[i];
      lons[i] = g.lon * kDegree;
      s = std::min(s, g.lat * kDegree);
      n = std::max(n, g.lat * kDegree);
      h0 = std::min(h0, g.height);
      h1 = std::max(h1, g.height);
    }
    // Longitudes from the tile's centre, so a tile across ±180° has a range
    // across it (east < west); a tile around a pole has every longitude and
    // reaches the pole.
    const BoundsOnGlobe globe = boundsOnGlobe(tile.bounds, *options.geo);
    LonRange lon = lonRangeAround(globe.centreLon, lons);
    if (globe.pole > 0) n = std::numbers::pi / 2;
    if (globe.pole < 0) s = -std::numbers::pi / 2;
    if (globe.pole != 0) lon = LonRange{};
    record.region = {lon.west, s, lon.east, n, h0, h1};
  } else {
    const encode::EnuFrame enu(options.localOrigin);
    for (std::size_t i = 0; i < project.size(); ++i) frame[i] = enu.fromGeodetic(geodetic[i]);
    record.local = true;
  }
  const encode::Box3 bounds = encode::boundingBox(frame);
  const Point3 centre = bounds.centre();
  if (record.local) {
    const Point3 &lo = bounds.lo, &hi = bounds.hi;
    record.box = {centre.x, centre.y, centre.z, 0.5 * (hi.x - lo.x), 0, 0, 0, 0.5 * (hi.y - lo.y),
                  0,        0,        0,        0.5 * (hi.z - lo.z)};
  }

  // Normals: area-weighted face normals of the surface in the output frame;
  // a skirt vertex takes the normal of the vertex above it.
  std::vector<Point3> normals = encode::areaWeightedNormals(frame, tile.triangles);
  for (std::size_t v = 0; v < top; ++v) {
    if (below[v] != std::numeric_limits<std::uint32_t>::max()) normals[below[v]] = normals[v];
  }
  const encode::MeshBuffers buffers = encode::meshBuffersAround(frame, normals, triangles, centre);

  encode::GlbOptions glb;
  glb.compression = options.compression;
  glb.maxPositionError = std::clamp(0.1 * tile.error, 0.0005, 0.01);
  // The record states the requested bound, which the encoder's actual one
  // never exceeds (the checkers compare decoded tiles against it).
  record.positionErrorBound =
      options.compression == encode::Compression::Draco ? glb.maxPositionError : 0.0;
  glb.assetExtras = recordToJson(record);
  encode::GlbResult result = encode::encodeGlb(buffers, encode::zUpContentRootMatrix(centre), glb);
  record.positionBits = result.positionBits;
  record.bytes = result.bytes.size();
  return {std::move(result.bytes), record};
}

}  // namespace tinsmith::tiles
