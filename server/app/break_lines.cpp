#include "server/app/break_lines.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <vector>

#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::server {

namespace {

using Json = nlohmann::ordered_json;
using Chain = std::vector<std::uint32_t>;

/// The edges (a < b) of one feature chained into polylines: each chain runs
/// between vertices whose degree is not 2 (ends, junctions), so it never
/// passes a junction; what is left are closed rings.
std::vector<Chain> chainEdges(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) {
  std::map<std::uint32_t, std::vector<std::uint32_t>> around;  // ordered: deterministic starts
  for (const auto& [a, b] : edges) {
    around[a].push_back(b);
    around[b].push_back(a);
  }
  for (auto& [v, list] : around) std::sort(list.begin(), list.end());
  std::map<std::pair<std::uint32_t, std::uint32_t>, bool> used;
  const auto key = [](std::uint32_t a, std::uint32_t b) {
    return std::pair(std::min(a, b), std::max(a, b));
  };
  const auto unusedFrom = [&](std::uint32_t v) -> std::optional<std::uint32_t> {
    for (const auto w : around[v])
      if (!used[key(v, w)]) return w;
    return std::nullopt;
  };
  std::vector<Chain> chains;
  const auto walk = [&](std::uint32_t start) {
    while (const auto first = unusedFrom(start)) {
      Chain chain{start};
      std::uint32_t at = *first;
      used[key(start, at)] = true;
      chain.push_back(at);
      while (around[at].size() == 2) {
        const auto next = unusedFrom(at);
        if (!next) break;  // a ring closed
        used[key(at, *next)] = true;
        at = *next;
        chain.push_back(at);
      }
      chains.push_back(std::move(chain));
    }
  };
  for (const auto& [v, list] : around)
    if (list.size() != 2) walk(v);
  for (const auto& [v, list] : around) walk(v);  // rings: every vertex has degree 2
  return chains;
}

double rounded(double v, double scale) {
  return std::round(v * scale) / scale;
}

}  // namespace

Json breakLinesGeoJson(const Tileset& tileset) {
  const Mesh& mesh = tileset.surface().mesh();
  std::map<std::uint32_t, std::vector<std::pair<std::uint32_t, std::uint32_t>>> byFeature;
  for (const auto& e : mesh.constrainedEdges()) byFeature[e.feature].emplace_back(e.a, e.b);

  struct Line {
    std::uint32_t feature;
    Chain chain;
  };
  std::vector<Line> lines;
  std::vector<Point3> points;
  for (const auto& [feature, edges] : byFeature)
    for (auto& chain : chainEdges(edges)) {
      for (const auto v : chain) points.push_back(mesh.point(VertexId(v)));
      lines.push_back({feature, std::move(chain)});
    }
  std::vector<encode::Geodetic> geodetic(points.size());
  tileset.toGeodetic(points, geodetic);

  Json features = Json::array();
  std::size_t next = 0;
  const auto& kinds = mesh.features();
  for (const auto& line : lines) {
    Json coordinates = Json::array();
    for (std::size_t i = 0; i < line.chain.size(); ++i, ++next) {
      const auto& g = geodetic[next];
      coordinates.push_back({rounded(g.lon, 1e8), rounded(g.lat, 1e8), rounded(g.height, 1e3)});
    }
    Json properties;
    properties["feature"] = line.feature;
    const bool known = line.feature < kinds.size();
    properties["kind"] = known ? ingest::featureKindName(kinds[line.feature].kind) : "other";
    properties["source"] = known ? kinds[line.feature].source : "";
    Json feature;
    feature["type"] = "Feature";
    feature["properties"] = std::move(properties);
    feature["geometry"] = {{"type", "LineString"}, {"coordinates", std::move(coordinates)}};
    features.push_back(std::move(feature));
  }
  Json out;
  out["type"] = "FeatureCollection";
  out["features"] = std::move(features);
  return out;
}

}  // namespace tinsmith::server
