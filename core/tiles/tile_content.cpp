#include "core/tiles/tile_content.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "core/base/error.hpp"
#include "core/encode/mesh_buffers.hpp"
#include "core/tiles/chord_sag.hpp"
#include "core/tiles/lon_range.hpp"
#include "core/tiles/shipped_error.hpp"

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

/// A local-frame box around the shipped positions (a box is convex, so it
/// holds every straight triangle between them).
std::array<double, 12> localBox(std::span<const Point3> shipped) {
  Point3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (const auto& p : shipped) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  return {0.5 * (lo.x + hi.x),
          0.5 * (lo.y + hi.y),
          0.5 * (lo.z + hi.z),
          0.5 * (hi.x - lo.x),
          0,
          0,
          0,
          0.5 * (hi.y - lo.y),
          0,
          0,
          0,
          0.5 * (hi.z - lo.z)};
}

/// The region (west, south, east, north in radians, heights in metres) of
/// what a client draws: the shipped ECEF positions and the straight
/// triangles between them, surface and skirts. A triangle's chords leave
/// the box of its corners — below their heights (a 20 km chord: 8 m) and, on
/// a parallel, poleward — so the region takes the middle of every edge and
/// the centre of every triangle, and its floor is each triangle's lowest
/// corner less its sag below its corners' heights (quadraticGapMax of its
/// edge middles').
std::array<double, 6> shippedRegion(const TileSurface& tile, std::span<const Point3> shipped,
                                    std::span<const std::array<std::uint32_t, 3>> triangles,
                                    const GeoReference& geo) {
  std::vector<encode::Geodetic> g(shipped.size());
  for (std::size_t i = 0; i < shipped.size(); ++i) g[i] = encode::ecefToGeodetic(shipped[i]);
  const auto edges = uniqueEdges(triangles);
  std::vector<encode::Geodetic> mid(edges.size());
  for (std::size_t k = 0; k < edges.size(); ++k) {
    mid[k] =
        encode::ecefToGeodetic(middle(shipped[edges[k] >> 32], shipped[edges[k] & 0xffffffffU]));
  }
  double s = HUGE_VAL, n = -HUGE_VAL, h0 = HUGE_VAL, h1 = -HUGE_VAL;
  std::vector<double> lons;
  lons.reserve(g.size() + mid.size() + triangles.size());
  auto take = [&](const encode::Geodetic& p) {
    lons.push_back(p.lon * kDegree);
    s = std::min(s, p.lat * kDegree);
    n = std::max(n, p.lat * kDegree);
    h1 = std::max(h1, p.height);
  };
  for (const auto& p : g) take(p);
  for (const auto& p : mid) take(p);
  for (const auto& t : triangles) {
    take(encode::ecefToGeodetic({(shipped[t[0]].x + shipped[t[1]].x + shipped[t[2]].x) / 3,
                                 (shipped[t[0]].y + shipped[t[1]].y + shipped[t[2]].y) / 3,
                                 (shipped[t[0]].z + shipped[t[1]].z + shipped[t[2]].z) / 3}));
    std::array<double, 3> depths{};
    double lowest = HUGE_VAL;
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = t[i], b = t[(i + 1) % 3];
      depths[i] =
          std::max(0.0, 0.5 * (g[a].height + g[b].height) - mid[edgeOf(edges, a, b)].height);
      lowest = std::min(lowest, g[a].height);
    }
    h0 = std::min(h0, lowest - quadraticGapMax(depths[0], depths[1], depths[2]));
  }
  // Longitudes from the tile's centre, so a tile across ±180° has a range
  // across it (east < west); a tile around a pole has every longitude and
  // reaches the pole.
  const BoundsOnGlobe globe = boundsOnGlobe(tile.bounds, geo);
  LonRange lon = lonRangeAround(globe.centreLon, lons);
  if (globe.pole > 0) n = std::numbers::pi / 2;
  if (globe.pole < 0) s = -std::numbers::pi / 2;
  if (globe.pole != 0) lon = LonRange{};
  return {lon.west, s, lon.east, n, h0, h1};
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
  // Only where it differs: most tiles have nothing out of reach.
  if (r.reachableError != r.error) j["reachableError"] = r.reachableError;
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
    r.reachableError = j.value("reachableError", r.error);
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
  record.breakLineVertices = tile.breakLineVertices;
  record.vertices = project.size();
  record.triangles = triangles.size();
  record.local = options.frame == ContentFrame::Local;

  const std::optional<encode::EnuFrame> enu =
      record.local ? std::optional<encode::EnuFrame>(options.localOrigin) : std::nullopt;
  auto toFrame = [&](const encode::Geodetic& g) {
    return enu ? enu->fromGeodetic(g) : encode::geodeticToEcef(g);
  };
  std::vector<Point3> frame(project.size());
  for (std::size_t i = 0; i < project.size(); ++i) frame[i] = toFrame(geodetic[i]);
  const Point3 centre = encode::boundingBox(frame).centre();

  // Normals: area-weighted face normals of the surface in the output frame;
  // a skirt vertex takes the normal of the vertex above it.
  std::vector<Point3> normals = encode::areaWeightedNormals(frame, tile.triangles);
  for (std::size_t v = 0; v < top; ++v) {
    if (below[v] != std::numeric_limits<std::uint32_t>::max()) normals[below[v]] = normals[v];
  }
  const encode::MeshBuffers buffers = encode::meshBuffersAround(frame, normals, triangles, centre);

  encode::GlbOptions glb;
  glb.compression = options.compression;
  // Quantization takes at most half of the tolerance's encoding share (the
  // tiler left kEncodingShare of it), and a tenth of an error well within
  // it; no finer than minQuantization where the share allows, nor coarser
  // than half the side margin the refiner kept. A tile over its tolerance
  // before encoding (its triangles cap reached, or chord sag the planning
  // underrated) takes the share and the tenth of that error instead: steps
  // a hundredth of a tolerance it misses by far cost bits, bytes and
  // Draco's time (3 mm across 3 000 km: 30 bits a coordinate).
  const EdgeSags sags = edgeSags(tile, project, frame, *options.geo, toFrame);
  const double unencoded = shippedError(tile, sags, frame, frame).all;
  const double missed = unencoded > tile.tolerance ? unencoded : 0.0;
  const double width = tile.bounds.width();
  const double share =
      tile.tolerance > 0 ? 0.5 * kEncodingShare * std::max(tile.tolerance, missed) : HUGE_VAL;
  const double coarsest = maxQuantization(width, tile.tolerance);
  const double finest =
      std::min(coarsest, std::max(0.0005, std::min(minQuantization(width), share)));
  glb.maxPositionError =
      std::clamp(std::min(0.1 * std::max(tile.error, missed), share), finest, coarsest);
  // The record states the requested bound, which the encoder's actual one
  // never exceeds (the checkers compare decoded tiles against it).
  record.positionErrorBound =
      options.compression == encode::Compression::Draco ? glb.maxPositionError : 0.0;

  // What a client draws: the decoded positions, straight triangles between them.
  const auto decoded = encode::decodedPositions(buffers, glb);
  std::vector<Point3> shipped(decoded.size());
  for (std::size_t i = 0; i < decoded.size(); ++i) {
    shipped[i] = {centre.x + decoded[i][0], centre.y + decoded[i][1], centre.z + decoded[i][2]};
  }
  const ShippedError error = shippedError(tile, sags, frame, shipped);
  record.error = error.all;
  record.reachableError = error.reachable;
  if (record.local) {
    record.box = localBox(shipped);
  } else {
    record.region = shippedRegion(tile, shipped, triangles, *options.geo);
  }
  glb.assetExtras = recordToJson(record);
  encode::GlbResult result = encode::encodeGlb(buffers, encode::zUpContentRootMatrix(centre), glb);
  record.positionBits = result.positionBits;
  record.bytes = result.bytes.size();
  return {std::move(result.bytes), record};
}

}  // namespace tinsmith::tiles
