#include "ingest/tinfile/tin_summary.hpp"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "ingest/tinfile/tin_file.hpp"
#include "ingest/tinfile/tin_view.hpp"
#include "core/geometry/predicates.hpp"

namespace tinsmith::ingest {

namespace {

// Counts, extent and z range: the part of the summary that reads only the
// vertices, from either view (tin_view.hpp).
template <class View>
void countGeometry(TinCounts& s, const View& tin) {
  const auto& vertices = tin.points();
  s.vertices = vertices.size();
  s.triangles = tin.triangleCount();
  if (vertices.empty()) return;
  const auto& v0 = vertices.front();
  s.minX = s.maxX = v0.x;
  s.minY = s.maxY = v0.y;
  s.minZ = s.maxZ = v0.z;
  for (const auto& v : vertices) {
    s.minX = std::min(s.minX, v.x);
    s.maxX = std::max(s.maxX, v.x);
    s.minY = std::min(s.minY, v.y);
    s.maxY = std::max(s.maxY, v.y);
    s.minZ = std::min(s.minZ, v.z);
    s.maxZ = std::max(s.maxZ, v.z);
  }
}

// The above, the area, and whether the TIN is empty.
template <class View>
void summariseGeometry(TinSummary& s, const View& tin) {
  countGeometry(s, tin);
  const auto& vertices = tin.points();
  s.empty = vertices.empty();
  for (std::size_t i = 0; i < s.triangles; ++i) {
    const auto t = tin.triangle(i);
    s.area += 0.5 * geometry::orient2dInexact(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  }
}

/// Distinct constrained edges of a mesh, and the edges of each feature kind.
std::size_t countConstrainedEdges(const Mesh& mesh, std::vector<std::size_t>* edgesOfKind) {
  const auto& features = mesh.features();
  std::size_t edges = 0;
  mesh.forEachConstrained([&](HalfedgeId h) {
    const HalfedgeId tw = mesh.twin(h);
    if (tw.valid() && tw.value < h.value) return;  // each edge once
    ++edges;
    if (edgesOfKind)
      for (const std::uint32_t f : mesh.edgeFeatures(h))
        if (f < features.size()) ++(*edgesOfKind)[static_cast<std::uint8_t>(features[f].kind)];
  });
  return edges;
}

}  // namespace

TinSummary summariseTin(const TinData& tin) {
  TinSummary s;
  s.crs = tin.crs;
  summariseGeometry(s, TinDataView{tin});
  // Distinct edges, as `tinsmith validate` counts them: an edge shared by
  // several features has one record per feature.
  {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    edges.reserve(tin.constrainedEdges.size());
    for (const auto& e : tin.constrainedEdges)
      edges.emplace_back(std::min(e.a, e.b), std::max(e.a, e.b));
    std::sort(edges.begin(), edges.end());
    s.constrainedEdges =
        static_cast<std::size_t>(std::unique(edges.begin(), edges.end()) - edges.begin());
  }
  s.features = tin.features.size();
  for (const auto& f : tin.features) ++s.kinds[std::string(featureKindName(f.kind))].features;
  for (const auto& e : tin.constrainedEdges)
    if (e.feature < tin.features.size())
      ++s.kinds[std::string(featureKindName(tin.features[e.feature].kind))].edges;
  return s;
}

TinSummary summariseTin(const Mesh& mesh) {
  TinSummary s;
  s.crs = mesh.crs();
  summariseGeometry(s, MeshView{mesh});
  const auto& features = mesh.features();
  s.features = features.size();
  for (const auto& f : features) ++s.kinds[std::string(featureKindName(f.kind))].features;
  std::vector<std::size_t> edgesOfKind(256, 0);
  s.constrainedEdges = countConstrainedEdges(mesh, &edgesOfKind);
  for (std::size_t k = 0; k < edgesOfKind.size(); ++k)
    if (edgesOfKind[k]) s.kinds[std::string(featureKindName(static_cast<FeatureKind>(k)))].edges = edgesOfKind[k];
  return s;
}

TinCounts countTin(const Mesh& mesh) {
  TinCounts s;
  countGeometry(s, MeshView{mesh});
  s.features = mesh.features().size();
  s.constrainedEdges = countConstrainedEdges(mesh, nullptr);
  return s;
}

std::string TinSummary::json() const {
  nlohmann::ordered_json j;
  if (!file.empty()) {
    j["file"] = file;
    j["bytes"] = fileBytes;
    j["format_version"] = formatVersion;
  }
  j["crs"] = crs;
  j["vertices"] = vertices;
  j["triangles"] = triangles;
  j["constrained_edges"] = constrainedEdges;
  j["features"] = features;
  if (empty) {
    j["extent"] = nullptr;
    j["z_range"] = nullptr;
  } else {
    j["extent"] = {minX, minY, maxX, maxY};
    j["z_range"] = {minZ, maxZ};
  }
  j["area_m2"] = area;
  nlohmann::ordered_json k = nlohmann::ordered_json::object();
  for (const auto& [name, c] : kinds) k[name] = {{"features", c.features}, {"constrained_edges", c.edges}};
  j["kinds"] = k;
  return j.dump(2) + "\n";
}

std::string TinSummary::text() const {
  std::ostringstream s;
  char buf[256];
  if (!file.empty())
    s << file << ": tinsmith TIN, format version " << formatVersion << ", " << fileBytes
      << " bytes\n";
  s << "  CRS: " << (crs.empty() ? "(unknown)" : crs) << "\n";
  s << "  " << vertices << " vertices, " << triangles << " triangles, " << constrainedEdges
    << " constrained edges, " << features << " features\n";
  if (!empty) {
    std::snprintf(buf, sizeof buf, "  extent: x %.3f .. %.3f, y %.3f .. %.3f (%.1f × %.1f m)\n",
                  minX, maxX, minY, maxY, maxX - minX, maxY - minY);
    s << buf;
    std::snprintf(buf, sizeof buf, "  z range: %.3f .. %.3f m\n  area: %.1f m²\n", minZ, maxZ, area);
    s << buf;
  }
  if (!kinds.empty()) {
    s << "  features by kind:\n";
    for (const auto& [name, c] : kinds)
      s << "    " << name << ": " << c.features << " features, " << c.edges << " constrained edges\n";
  }
  return s.str();
}

}  // namespace tinsmith::ingest
