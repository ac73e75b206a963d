#include "tools/cli/tile_summary.hpp"

#include <cstdio>
#include <nlohmann/json.hpp>

namespace tinsmith::cli {

namespace {
std::string format(const char* fmt, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}
}  // namespace

std::string tileSummaryText(const ingest::TileJobSummary& s) {
  std::string out = format(
      "  tiles: %zu in %zu zooms, %.2f MB (finest planned zoom %d, %d binary levels a tile)\n",
      s.tiles, s.zooms.size(), static_cast<double>(s.bytes) / 1e6, s.finestZoom,
      s.levelsPerTile + 1);
  if (s.built + s.reused > 0) {
    out += format("  built %zu, kept %zu already in the store, %zu fit points, %.1f s\n", s.built,
                  s.reused, s.dataPoints, s.seconds);
  }
  out +=
      "  zoom  tolerance m  tiles  triangles  bytes/triangle  max error m  break-line vertices\n";
  for (const auto& z : s.zooms) {
    out +=
        format("  %4d  %11.3f  %5zu  %9zu  %14.2f  %11.3f  %19zu\n", z.z, z.tolerance, z.tiles,
               z.triangles,
               z.triangles ? static_cast<double>(z.bytes) / static_cast<double>(z.triangles) : 0.0,
               z.maxError, z.breakLineVertices);
  }
  return out;
}

nlohmann::ordered_json tileSummaryObject(const ingest::TileJobSummary& s,
                                         const std::string& output) {
  nlohmann::ordered_json j;
  j["output"] = output;
  j["tiles"] = s.tiles;
  j["bytes"] = s.bytes;
  j["built"] = s.built;
  j["kept"] = s.reused;
  j["finestZoom"] = s.finestZoom;
  j["levelsPerTile"] = s.levelsPerTile;
  j["fitPoints"] = s.dataPoints;
  j["seconds"] = s.seconds;
  auto zooms = nlohmann::ordered_json::array();
  for (const auto& z : s.zooms) {
    zooms.push_back({{"zoom", z.z},
                     {"tolerance", z.tolerance},
                     {"tiles", z.tiles},
                     {"triangles", z.triangles},
                     {"vertices", z.vertices},
                     {"bytes", z.bytes},
                     {"maxError", z.maxError},
                     {"breakLineVertices", z.breakLineVertices}});
  }
  j["zooms"] = zooms;
  return j;
}

std::string tileSummaryJson(const ingest::TileJobSummary& s, const std::string& output) {
  return tileSummaryObject(s, output).dump(2) + "\n";
}

}  // namespace tinsmith::cli
