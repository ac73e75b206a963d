#include "ingest/tiles/terrain_job.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <map>
#include <set>

#include "core/base/error.hpp"
#include "core/encode/quantized_mesh.hpp"
#include "core/tiles/geographic_grid.hpp"
#include "core/tiles/pyramid_build.hpp"
#include "core/tiles/terrain_content.hpp"
#include "core/tiles/terrain_tiling.hpp"

namespace tinsmith::ingest {

namespace fs = std::filesystem;
using tiles::TileId;
using tiles::TileRecord;

namespace {

/// Levels a tile's metadata tells the availability of (0, 10, 20 … carry it).
constexpr int kMetadataLevels = 10;

nlohmann::ordered_json layerJson(const std::vector<TileId>& gridTiles, int levels,
                                 const tiles::GeoRect& bounds, const std::string& attribution) {
  nlohmann::ordered_json j;
  j["tilejson"] = "2.1.0";
  j["name"] = "tinsmith terrain";
  j["description"] = "quantized-mesh terrain built by tinsmith from a constrained TIN";
  j["version"] = "1.0.0";
  j["format"] = "quantized-mesh-1.0";
  j["attribution"] = attribution;
  j["scheme"] = "tms";
  j["tiles"] = {"{z}/{x}/{y}.terrain"};
  j["projection"] = "EPSG:4326";
  j["bounds"] = {bounds.west, bounds.south, bounds.east, bounds.north};
  j["minzoom"] = 0;
  j["maxzoom"] = levels - 1;
  j["extensions"] = {"octvertexnormals", "watermask", "metadata"};
  // Tiles of levels 0, 10, 20 tell the next ten levels' availability: a
  // client that reads metadata (CesiumJS) needs to be told, or fails on
  // every tile.
  j["metadataAvailability"] = kMetadataLevels;
  j["available"] = availableRanges(gridTiles, levels);
  return j;
}

}  // namespace

std::optional<TileId> gridTileOfKey(std::string_view key) {
  constexpr std::string_view kPrefix = "terrain/", kSuffix = ".terrain";
  if (!key.starts_with(kPrefix) || !key.ends_with(kSuffix)) return std::nullopt;
  std::string_view rest = key.substr(kPrefix.size(), key.size() - kPrefix.size() - kSuffix.size());
  std::array<std::uint32_t, 3> zxy{};
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t slash = i < 2 ? rest.find('/') : rest.size();
    if (slash == std::string_view::npos || slash == 0) return std::nullopt;
    const auto [end, ec] = std::from_chars(rest.data(), rest.data() + slash, zxy[i]);
    if (ec != std::errc{} || end != rest.data() + slash) return std::nullopt;
    rest = rest.substr(std::min(slash + 1, rest.size()));
  }
  if (zxy[0] > 30) return std::nullopt;
  const TileId id{static_cast<int>(zxy[0]), zxy[1], zxy[2]};
  if (!tiles::isGeographicTile(id)) return std::nullopt;
  return id;
}

std::string terrainTileKey(const TileId& t) {
  return "terrain/" + std::to_string(t.z) + "/" + std::to_string(t.x) + "/" + std::to_string(t.y) +
         ".terrain";
}

nlohmann::ordered_json availableRanges(std::vector<TileId> tiles, int levels) {
  std::sort(tiles.begin(), tiles.end(), tiles::rowMajorLess);
  auto out = nlohmann::ordered_json::array();
  for (int level = 0; level < levels; ++level) {
    // Runs of columns per row, then runs of equal rows.
    struct Range {
      std::uint32_t startX, endX, startY, endY;
    };
    std::vector<Range> rows;
    for (const auto& t : tiles) {
      if (t.z != level) continue;
      if (!rows.empty() && rows.back().startY == t.y && rows.back().endX + 1 == t.x) {
        rows.back().endX = t.x;
      } else {
        rows.push_back({t.x, t.x, t.y, t.y});
      }
    }
    std::vector<Range> joined;
    for (const Range& r : rows) {
      auto above = std::find_if(joined.begin(), joined.end(), [&](const Range& j) {
        return j.startX == r.startX && j.endX == r.endX && j.endY + 1 == r.startY;
      });
      if (above != joined.end()) {
        above->endY = r.endY;
      } else {
        joined.push_back(r);
      }
    }
    auto ranges = nlohmann::ordered_json::array();
    for (const Range& r : joined)
      ranges.push_back(
          {{"startX", r.startX}, {"startY", r.startY}, {"endX", r.endX}, {"endY", r.endY}});
    out.push_back(ranges);
  }
  return out;
}

TerrainSummary tileTerrain(const tiles::GeographicTin& frame, const TileJobOptions& options,
                           store::TileStore& stage, const store::TileStore* previous,
                           std::vector<std::string>& keys, const Progress* progress) {
  reportProgress(progress, "terrain.plan", "", 0, 0);
  const int finestLevel = tiles::terrainLevelFor(options.tiler.tolerance);
  tiles::TilerOptions tilerOptions = options.tiler;
  tilerOptions.maxZoom.reset();  // the 3D Tiles' zooms are not the grid's levels
  tilerOptions.threads = options.threads;
  tilerOptions = tiles::terrainTilerOptions(tilerOptions, frame.west, finestLevel);
  const tiles::Tiler tiler(frame.tin, tilerOptions);
  reportProgress(progress, "terrain.plan", "", 1, 1);

  std::vector<tiles::TerrainLine> lakes;
  for (auto& line : tiles::extractTerrainLines(frame.tin))
    if (line.kind == FeatureKind::Lake && line.closed) lakes.push_back(std::move(line));
  const tiles::TerrainTileOptions content{frame.west, &lakes};
  const auto gridTile = [&](const TileId& id) { return *tiles::geographicTileOf(id, frame.west); };
  const tiles::TileEncoder encode = [&](const tiles::TileSurface& s) {
    if (s.id.z == 0) return tiles::TileContent{{}, TileRecord{.id = s.id}};  // the frame's root
    tiles::TileContent c = tiles::encodeTerrainTile(s, s.id, tiler.geometry(), content);
    // Quantization to 0..32767 over the tile's heights — from 0 where the
    // ellipsoid fills in beside the TIN — can move a vertex farther than the
    // tiler's encoding share (22 mm for 1.5 km of height, against 6 mm of a
    // 0.29 m level): refine again short of the tolerance by what it moved.
    if (c.record.error > tiler.zoomTolerance(s.id.z)) {
      const tiles::TileSurface tighter = tiler.buildTile(s.id, 1.25 * c.record.positionErrorBound);
      tiles::TileContent again = tiles::encodeTerrainTile(tighter, s.id, tiler.geometry(), content);
      if (again.record.error < c.record.error) c = std::move(again);
    }
    return c;
  };

  tiles::PyramidCallbacks callbacks;
  if (options.resume) {
    callbacks.existing = [&](const TileId& id) -> std::optional<TileRecord> {
      if (id.z == 0) return std::nullopt;
      const std::string key = terrainTileKey(gridTile(id));
      auto bytes = stage.get(key);
      if (!bytes && previous) {
        bytes = previous->get(key);
        if (bytes) stage.put(key, *bytes);
      }
      if (!bytes) return std::nullopt;
      auto record = tiles::recordFromTerrainTile(*bytes);
      if (!record || record->id != gridTile(id)) return std::nullopt;
      record->id = id;
      record->bytes = bytes->size();
      return record;
    };
  }
  callbacks.emit = [&](const tiles::TileContent& c) {
    if (c.record.id.z > 0) stage.put(terrainTileKey(gridTile(c.record.id)), c.glb);
  };
  callbacks.progress = [&](int z, std::size_t done, std::size_t total) {
    if (z > 0)
      reportProgress(progress, "terrain.level", "level " + std::to_string(z - 1), done, total);
  };
  const tiles::PyramidSummary walked =
      tiles::buildPyramid(tiler, encode, TileId{}, options.threads, callbacks);

  TerrainSummary summary;
  summary.finestLevel = finestLevel;
  // The frame's root (no tile of the grid) is walked, never stored.
  const bool rootWalked = std::any_of(walked.records.begin(), walked.records.end(),
                                      [](const TileRecord& r) { return r.id.z == 0; });
  summary.built = walked.built - (rootWalked ? 1 : 0);
  summary.reused = walked.reused;
  std::vector<TileRecord> records;
  for (const auto& r : walked.records)
    if (r.id.z > 0) records.push_back(r);
  // Both level-0 tiles, whether the TIN reaches them or not.
  for (std::uint32_t x = 0; x < 2; ++x) {
    const TileId id{1, x, 0};
    if (std::any_of(records.begin(), records.end(), [&](const auto& r) { return r.id == id; }))
      continue;
    tiles::TileSurface none;
    none.id = id;
    tiles::TileContent c = tiles::encodeTerrainTile(none, id, tiler.geometry(), content);
    stage.put(terrainTileKey(gridTile(id)), c.glb);
    records.push_back(c.record);
    ++summary.built;
  }
  std::sort(records.begin(), records.end(), [&](const TileRecord& a, const TileRecord& b) {
    return tiles::rowMajorLess(gridTile(a.id), gridTile(b.id));
  });

  // Availability in the metadata of levels 0, 10, 20: the tiles of the next
  // ten levels under each.
  std::vector<TileId> grid;
  for (const auto& r : records) grid.push_back(gridTile(r.id));
  for (const TileId& top : grid) {
    if (top.z % kMetadataLevels != 0) continue;
    std::vector<TileId> below;
    for (const TileId& t : grid) {
      const int dz = t.z - top.z;
      if (dz >= 1 && dz <= kMetadataLevels && (t.x >> dz) == top.x && (t.y >> dz) == top.y)
        below.push_back({dz - 1, t.x, t.y});
    }
    const std::string key = terrainTileKey(top);
    const std::string bytes = *stage.get(key);
    auto metadata = nlohmann::ordered_json::parse(encode::quantizedMeshMetadata(bytes).value());
    metadata["available"] = availableRanges(below, kMetadataLevels);
    // Trailing levels with nothing are left out.
    auto& available = metadata["available"];
    while (!available.empty() && available.back().empty()) available.erase(available.size() - 1);
    if (available.empty()) metadata.erase("available");
    stage.put(key, encode::withMetadata(bytes, metadata.dump()));
  }

  // The summary and layer.json, from the records.
  std::vector<TerrainTileEntry> entries;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const std::string key = terrainTileKey(grid[i]);
    entries.push_back({grid[i], records[i], stage.get(key)->size()});
    keys.push_back(key);
  }
  TerrainSummary described = summarizeTerrain(entries);
  described.finestLevel = summary.finestLevel;
  described.built = summary.built;
  described.reused = summary.reused;
  summary = std::move(described);
  // The TIN's extent as layer.json's bounds; across the antimeridian west >
  // east (the frame's x run on past 180°), as TileJSON reads them.
  const tiles::Rect extent = tiles::boundsOf(frame.tin.vertices);
  const auto longitude = [](double x) {
    const double lon = x / tiles::kMetresPerDegree;
    return lon > 180 ? lon - 360 : lon;
  };
  const tiles::GeoRect bounds{longitude(extent.x0), extent.y0 / tiles::kMetresPerDegree,
                              longitude(extent.x1), extent.y1 / tiles::kMetresPerDegree};
  const std::string attribution =
      options.attribution.empty() ? "Terrain: tinsmith" : options.attribution;
  const int levels = summary.levels.empty() ? 1 : summary.levels.back().z + 1;
  const std::string layer = layerJson(grid, levels, bounds, attribution).dump(2) + "\n";
  stage.put(kTerrainLayerKey, layer);
  summary.bytes += layer.size();
  keys.push_back(kTerrainLayerKey);
  return summary;
}

TerrainSummary summarizeTerrain(const std::vector<TerrainTileEntry>& tiles) {
  TerrainSummary summary;
  std::map<int, ZoomSummary> levels;
  for (const auto& [grid, r, bytes] : tiles) {
    auto& z = levels[grid.z];
    z.z = grid.z;
    z.tolerance = tiles::cesiumLevelMaximumGeometricError(grid.z);
    ++z.tiles;
    z.triangles += r.triangles;
    z.vertices += r.vertices;
    z.bytes += bytes;
    z.breakLineVertices += r.breakLineVertices;
    z.maxError = std::max(z.maxError, r.error);
    if (r.error > z.tolerance) {
      ++z.overTolerance;
      summary.missed.push_back({grid, r.error, z.tolerance, r.reachableError});
    }
    summary.bytes += bytes;
  }
  for (auto& [z, s] : levels) summary.levels.push_back(s);
  summary.tiles = tiles.size();
  return summary;
}

std::optional<TerrainSummary> describeTerrain(const store::TileStore& store) {
  std::vector<TerrainTileEntry> entries;
  for (const auto& key : store.keys()) {
    if (!key.starts_with("terrain/") || !key.ends_with(".terrain")) continue;
    const auto grid = gridTileOfKey(key);
    if (!grid)
      throw inputError("'" + key + "' is no tile of the geographic grid",
                       fileLocation(store.path()),
                       "terrain/{level}/{x}/{y}.terrain with x < 2^(level+1), y < 2^level");
    const auto bytes = store.get(key);
    if (!bytes) continue;
    const auto record = tiles::recordFromTerrainTile(*bytes);
    if (!record || record->id != *grid)
      throw inputError(
          "the terrain tile " + key + " carries no tinsmith record of its own in its metadata",
          fileLocation(store.path()),
          "rebuild the terrain with tinsmith tile --scheme quantized-mesh");
    entries.push_back({*grid, *record, bytes->size()});
  }
  const auto layer = store.get(kTerrainLayerKey);
  if (entries.empty() && !layer) return std::nullopt;
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return tiles::rowMajorLess(a.grid, b.grid); });
  TerrainSummary summary = summarizeTerrain(entries);
  if (!summary.levels.empty()) summary.finestLevel = summary.levels.back().z;
  if (layer) {
    summary.bytes += layer->size();
    const auto json = nlohmann::json::parse(*layer, nullptr, false);
    if (json.is_object() && json.contains("maxzoom") && json["maxzoom"].is_number_integer())
      summary.finestLevel = json["maxzoom"].get<int>();
  }
  return summary;
}

}  // namespace tinsmith::ingest
