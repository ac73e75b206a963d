#include "tools/cli/tile_summary.hpp"

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace tinsmith::cli {

namespace {
std::string format(const char* fmt, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}
std::string terrainText(const ingest::TerrainSummary& t) {
  std::string out =
      format("  Cesium terrain: %zu tiles in %zu levels, %.2f MB (finest level %d)", t.tiles,
             t.levels.size(), static_cast<double>(t.bytes) / 1e6, t.finestLevel);
  // A store described (tinsmith info) was not built by this run.
  out += t.built + t.reused > 0 ? format(", built %zu, kept %zu\n", t.built, t.reused) : "\n";
  out += "  level  Cesium error m  tiles  triangles  bytes/tile  max error m  over\n";
  for (const auto& z : t.levels) {
    out += format("  %5d  %14.3f  %5zu  %9zu  %10.0f  %11.3f  %4zu\n", z.z, z.tolerance, z.tiles,
                  z.triangles, static_cast<double>(z.bytes) / static_cast<double>(z.tiles),
                  z.maxError, z.overTolerance);
  }
  return out;
}
std::string processText(const ingest::TileJobSummary& s) {
  if (s.cpuSeconds <= 0 && s.peakMemoryBytes == 0) return "";
  return format("  process: CPU %.2f s, peak memory %.0f MB\n", s.cpuSeconds,
                static_cast<double>(s.peakMemoryBytes) / 1e6);
}
}  // namespace

std::string tileSummaryText(const ingest::TileJobSummary& s) {
  std::string out;
  // Cesium terrain alone (--scheme quantized-mesh) has no 3D Tiles to tell of.
  if (s.zooms.empty() && s.terrain) {
    if (s.seconds > 0) out += format("  %.1f s\n", s.seconds);
    return out + terrainText(*s.terrain) + processText(s);
  }
  out += format(
      "  tiles: %zu in %zu zooms, %.2f MB (finest planned zoom %d, %d binary levels a tile)\n",
      s.tiles, s.zooms.size(), static_cast<double>(s.bytes) / 1e6, s.finestZoom,
      s.levelsPerTile + 1);
  if (s.built + s.reused > 0) {
    out += format("  built %zu, kept %zu already in the store, %zu fit points, %.1f s\n", s.built,
                  s.reused, s.dataPoints, s.seconds);
  }
  if (s.leftAboveZoom > 0) {
    out += format(
        "  the tiles above zoom %d are the merge's (tinsmith merge builds them from the zoom-%d "
        "tiles' surfaces); this shard hands over %zu of them\n",
        s.leftAboveZoom, s.leftAboveZoom, s.surfacesHandedOver);
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
  if (s.terrain) out += terrainText(*s.terrain);
  return out + processText(s);
}

std::string missedToleranceText(const ingest::TileJobSummary& s) {
  std::string terrain;
  if (s.terrain && !s.terrain->missed.empty()) {
    const auto& m = s.terrain->missed;
    terrain = format(
        "WARNING: %zu Cesium terrain tiles are over their level's error; the first: "
        "%s %.3f m against %.3f m (CesiumJS picks them for their level's error)\n",
        m.size(), m[0].id.name().c_str(), m[0].error, m[0].tolerance);
  }
  if (s.missed.empty()) return terrain;
  std::vector<ingest::MissedTile> worst = s.missed;
  std::stable_sort(worst.begin(), worst.end(), [](const auto& a, const auto& b) {
    return a.error / a.tolerance > b.error / b.tolerance;
  });
  std::string zooms;
  for (const auto& z : s.zooms)
    if (z.overTolerance > 0) zooms += (zooms.empty() ? "" : ", ") + std::to_string(z.z);
  std::string out =
      format("WARNING: %zu of %zu tiles are over their zoom's tolerance (zoom%s ", s.missed.size(),
             s.tiles, zooms.find(',') != std::string::npos ? "s" : "");
  out += zooms + "); the worst:";
  for (std::size_t i = 0; i < std::min<std::size_t>(worst.size(), 5); ++i)
    out += format("%s %s %.3f m against %.3f m", i ? "," : "", worst[i].id.name().c_str(),
                  worst[i].error, worst[i].tolerance);
  out +=
      "\n  their geometricError is what they measure, so viewers refine them sooner; "
      "a larger --max-triangles or a looser --tolerance may meet it (--strict: exit code 1)\n";
  const auto unreachable = static_cast<std::size_t>(std::count_if(
      s.missed.begin(), s.missed.end(), [](const auto& m) { return m.outOfReach(); }));
  if (unreachable > 0) {
    out += format(
        "  %zu of them miss only within the side margin (2 cm) of a tile side, where no tile "
        "below can add a vertex either (a spike or pit at a side): from the planned finest zoom "
        "on they get no children for it\n",
        unreachable);
  }
  return out + terrain;
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
  if (s.leftAboveZoom > 0) {
    j["leftAboveZoom"] = s.leftAboveZoom;
    j["surfacesHandedOver"] = s.surfacesHandedOver;
  }
  if (s.cpuSeconds > 0 || s.peakMemoryBytes > 0) {
    j["cpuSeconds"] = s.cpuSeconds;
    j["peakMemoryBytes"] = s.peakMemoryBytes;
  }
  auto zooms = nlohmann::ordered_json::array();
  for (const auto& z : s.zooms) {
    zooms.push_back({{"zoom", z.z},
                     {"tolerance", z.tolerance},
                     {"tiles", z.tiles},
                     {"triangles", z.triangles},
                     {"vertices", z.vertices},
                     {"bytes", z.bytes},
                     {"maxError", z.maxError},
                     {"overTolerance", z.overTolerance},
                     {"breakLineVertices", z.breakLineVertices}});
  }
  j["zooms"] = zooms;
  auto missed = nlohmann::ordered_json::array();
  for (const auto& m : s.missed)
    missed.push_back({{"tile", m.id.name()},
                      {"error", m.error},
                      {"tolerance", m.tolerance},
                      {"outOfReach", m.outOfReach()}});
  j["withinTolerance"] = s.missed.empty();
  j["overTolerance"] = missed;
  if (s.terrain) {
    const auto& t = *s.terrain;
    nlohmann::ordered_json tj;
    tj["tiles"] = t.tiles;
    tj["bytes"] = t.bytes;
    tj["built"] = t.built;
    tj["kept"] = t.reused;
    tj["finestLevel"] = t.finestLevel;
    auto levels = nlohmann::ordered_json::array();
    for (const auto& z : t.levels)
      levels.push_back({{"level", z.z},
                        {"cesiumError", z.tolerance},
                        {"tiles", z.tiles},
                        {"triangles", z.triangles},
                        {"vertices", z.vertices},
                        {"bytes", z.bytes},
                        {"maxError", z.maxError},
                        {"overError", z.overTolerance}});
    tj["levels"] = levels;
    auto over = nlohmann::ordered_json::array();
    for (const auto& m : t.missed)
      over.push_back({{"tile", m.id.name()}, {"error", m.error}, {"cesiumError", m.tolerance}});
    tj["withinLevelErrors"] = t.missed.empty();
    tj["overError"] = over;
    j["terrain"] = tj;
  }
  return j;
}

std::string tileSummaryJson(const ingest::TileJobSummary& s, const std::string& output) {
  return tileSummaryObject(s, output).dump(2) + "\n";
}

}  // namespace tinsmith::cli
