#include "ingest/tiles/tile_job.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <nlohmann/json.hpp>

#include "core/base/error.hpp"
#include "core/tiles/pyramid_build.hpp"
#include "core/tiles/tileset_json.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::ingest {

namespace fs = std::filesystem;
using tiles::TileId;
using tiles::TileRecord;

namespace {

constexpr const char* kBuildKey = "tinsmith/build.json";
constexpr const char* kTinKey = "tinsmith/terrain.tin";

std::string compressionName(encode::Compression c) {
  return c == encode::Compression::Draco ? "draco" : "none";
}

/// What the tiles are a function of (and nothing else: no subtree, no
/// threads, no time), so shards and resumed runs can be checked against it.
std::string buildRecord(const TinData& tin, const std::string& tinBytes, const std::string& tinName,
                        const TileJobOptions& o, const tiles::Tiler& tiler) {
  nlohmann::ordered_json j;
  j["format"] = "tinsmith-tiles/1";
  j["tin"] = {{"name", fs::path(tinName).filename().string()},
              {"crc32", crc32(tinBytes)},
              {"vertices", tin.vertices.size()},
              {"triangles", tin.triangles.size()},
              {"crs", tin.crs}};
  j["options"] = {{"tolerance", o.tiler.tolerance},
                  {"maxTriangles", o.tiler.maxTriangles},
                  {"maxZoom", tiler.maxZoom()},
                  {"lambdaFactor", o.tiler.lambdaFactor},
                  {"compression", compressionName(o.compression)},
                  {"frame", o.frame == tiles::ContentFrame::Ecef ? "ecef" : "local"},
                  {"geoid", o.geoid}};
  j["pyramid"] = {{"origin", {tiler.geometry().origin().x, tiler.geometry().origin().y}},
                  {"size", tiler.geometry().size()},
                  {"finestZoom", tiler.finestZoom()},
                  {"levelsPerTile", tiler.levelsPerTile()}};
  return j.dump(2) + "\n";
}

bool tileKeyLess(const std::string& a, const std::string& b,
                 const std::map<std::string, TileId>& ids) {
  return ids.at(a) < ids.at(b);
}

/// The canonical order of a finished store's keys.
std::vector<std::string> canonicalKeys(const std::vector<std::string>& keys) {
  std::vector<std::string> head, tileKeys, tail;
  std::map<std::string, TileId> ids;
  for (const auto& k : keys) {
    if (k == kBuildKey || k == kTinKey) {
      head.push_back(k);
    } else if (k.rfind("tiles/", 0) == 0) {
      unsigned z = 0, x = 0, y = 0;
      if (std::sscanf(k.c_str(), "tiles/%u/%u/%u.glb", &z, &x, &y) == 3) {
        ids[k] = TileId{static_cast<int>(z), y, x};  // ordered (z, y, x)
        tileKeys.push_back(k);
      }
    } else if (k.rfind("tilesets/", 0) == 0 || k == "tileset.json") {
      tail.push_back(k);
    }
  }
  std::sort(head.begin(), head.end());
  std::sort(tileKeys.begin(), tileKeys.end(),
            [&](auto& a, auto& b) { return tileKeyLess(a, b, ids); });
  std::sort(tail.begin(), tail.end());
  std::vector<std::string> out = head;
  out.insert(out.end(), tileKeys.begin(), tileKeys.end());
  out.insert(out.end(), tail.begin(), tail.end());
  return out;
}

std::string tilesetExtras(const std::string& build) {
  const auto b = nlohmann::json::parse(build);
  nlohmann::ordered_json e;
  e["tinsmith"] = {{"crs", b["tin"]["crs"]},
                   {"tolerance", b["options"]["tolerance"]},
                   {"finestZoom", b["pyramid"]["finestZoom"]}};
  return e.dump();
}

TileJobSummary summarize(const std::vector<TileRecord>& records, const std::string& build) {
  TileJobSummary s;
  const auto b = nlohmann::json::parse(build, nullptr, false);
  const double tolerance = b.is_discarded() ? 0.0 : b["options"].value("tolerance", 0.0);
  s.finestZoom = b.is_discarded() ? 0 : b["pyramid"].value("finestZoom", 0);
  s.levelsPerTile = b.is_discarded() ? 0 : b["pyramid"].value("levelsPerTile", 0);
  std::map<int, ZoomSummary> zooms;
  for (const auto& r : records) {
    auto& z = zooms[r.id.z];
    z.z = r.id.z;
    z.tolerance = std::ldexp(tolerance, std::max(0, s.finestZoom - r.id.z));
    ++z.tiles;
    z.triangles += r.triangles;
    z.vertices += r.vertices;
    z.bytes += r.bytes;
    z.breakLineVertices += r.breakLineVertices;
    z.maxError = std::max(z.maxError, r.error);
    s.bytes += r.bytes;
  }
  for (auto& [z, summary] : zooms) s.zooms.push_back(summary);
  s.tiles = records.size();
  return s;
}

/// Records of every tile in a store, from the tiles themselves.
std::vector<TileRecord> storeRecords(const store::TileStore& st,
                                     std::map<TileId, std::string>* keysOut = nullptr) {
  std::vector<TileRecord> records;
  for (const auto& key : st.keys()) {
    if (key.rfind("tiles/", 0) != 0) continue;
    const auto bytes = st.get(key);
    const auto record = bytes ? tiles::recordFromGlb(*bytes) : std::nullopt;
    if (!record) {
      throw inputError("tile " + key + " in " + st.path().string() + " is not a tinsmith tile", {},
                       "rebuild the store with tinsmith tile");
    }
    if (tiles::tileContentKey(record->id) != key) {
      throw inputError("tile " + key + " in " + st.path().string() + " says it is " +
                       record->id.name());
    }
    records.push_back(*record);
    records.back().bytes = bytes->size();
    if (keysOut) (*keysOut)[record->id] = key;
  }
  std::sort(records.begin(), records.end(), [](const TileRecord& a, const TileRecord& b) {
    return a.id.z < b.id.z ||
           (a.id.z == b.id.z && (a.id.y < b.id.y || (a.id.y == b.id.y && a.id.x < b.id.x)));
  });
  return records;
}

/// Writes the tileset files from the records and, for an archive, the
/// finished store in canonical order; removes the staging archive.
void finish(store::TileStore& stage, const fs::path& output, const std::vector<TileRecord>& records,
            const std::string& build) {
  tiles::TilesetOptions tileset;
  tileset.extras = tilesetExtras(build);
  for (const auto& [key, json] : tiles::tilesetFiles(records, tileset)) stage.put(key, json);
  if (stage.path() != output) {
    store::writeStore(stage, canonicalKeys(stage.keys()), output);
  }
}

fs::path stagingPath(const fs::path& output) {
  if (store::storeKindFor(output) == store::StoreKind::Directory) return output;
  fs::path stage = output;
  stage.replace_extension(".partial.3dtiles");
  return stage;
}

}  // namespace

TileJobSummary runTileJob(const TinData& tin, const std::string& tinName, const fs::path& output,
                          const TileJobOptions& options, const Progress* progress) {
  const auto start = std::chrono::steady_clock::now();
  tiles::TilerOptions tilerOptions = options.tiler;
  tilerOptions.threads = options.threads;
  reportProgress(progress, "tiles.plan", "", 0, 0);
  const tiles::Tiler tiler(tin, tilerOptions);
  reportProgress(progress, "tiles.plan", "", 1, 1);

  std::unique_ptr<ProjGeoReference> geo;
  tiles::ContentOptions content;
  content.compression = options.compression;
  content.frame = options.frame;
  if (options.frame == tiles::ContentFrame::Ecef || !tin.crs.empty()) {
    geo = std::make_unique<ProjGeoReference>(tin.crs, options.geoid);
    content.geo = geo.get();
    const Point2 o = tiler.geometry().origin();
    const double h = 0.5 * tiler.geometry().size();
    const Point3 centre{o.x + h, o.y + h, 0.0};
    encode::Geodetic g;
    geo->toGeodetic({&centre, 1}, {&g, 1});
    content.localOrigin = g;
  } else {
    throw inputError("--frame local needs the TIN's CRS to place east-north-up axes", {},
                     "rebuild the TIN with --crs");
  }

  const std::string tinBytes = encodeTin(tin);
  const std::string build = buildRecord(tin, tinBytes, tinName, options, tiler);
  const fs::path stagePath = stagingPath(output);
  auto stage = store::openStoreForWriting(stagePath, options.resume);
  if (options.resume) {
    const auto previous = stage->get(kBuildKey);
    if (previous && *previous != build) {
      throw usageError(
          "the store " + stagePath.string() + " was built from another TIN or other options",
          "run without --resume to start over, or with the options it was built with");
    }
  }
  stage->put(kBuildKey, build);
  if (!stage->contains(kTinKey)) stage->put(kTinKey, tinBytes);

  tiles::PyramidCallbacks callbacks;
  if (options.resume) {
    callbacks.existing = [&](const TileId& id) -> std::optional<TileRecord> {
      const auto bytes = stage->get(tiles::tileContentKey(id));
      return bytes ? tiles::recordFromGlb(*bytes) : std::nullopt;
    };
  }
  const int untilZoom = options.untilZoom.value_or(1 << 20);
  callbacks.emit = [&](const tiles::TileContent& c) {
    stage->put(tiles::tileContentKey(c.record.id), c.glb);
  };
  callbacks.progress = [&](int z, std::size_t done, std::size_t total) {
    reportProgress(progress, "tiles.zoom", "zoom " + std::to_string(z), done, total);
  };
  const TileId root = options.subtree.value_or(TileId{});
  const tiles::PyramidSummary walked =
      tiles::buildPyramid(tiler, content, root, options.threads, callbacks, untilZoom);

  std::vector<TileRecord> records = storeRecords(*stage);
  const bool whole = !options.subtree && !options.untilZoom;
  if (whole) {
    finish(*stage, output, records, build);
    if (stagePath != output) fs::remove(stagePath);
  } else {
    // A shard: no tileset.json of its own; `tinsmith merge` writes it.
    if (stagePath != output) {
      store::writeStore(*stage, canonicalKeys(stage->keys()), output);
      fs::remove(stagePath);
    }
  }
  TileJobSummary summary = summarize(records, build);
  summary.built = walked.built;
  summary.reused = walked.reused;
  summary.dataPoints = tiler.dataPointCount();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

TileJobSummary mergeTileStores(const std::vector<fs::path>& inputs, const fs::path& output) {
  if (inputs.empty())
    throw usageError("nothing to merge", "name the shard stores: tinsmith merge A B … -o ALL");
  const fs::path stagePath = stagingPath(output);
  auto stage = store::openStoreForWriting(stagePath, false);
  std::string build;
  for (const auto& path : inputs) {
    auto in = store::openStoreForReading(path);
    const auto b = in->get(kBuildKey);
    if (!b)
      throw inputError(path.string() + " is not a tinsmith tile store (no " + kBuildKey + ")");
    if (build.empty()) {
      build = *b;
      stage->put(kBuildKey, build);
      if (auto tin = in->get(kTinKey)) stage->put(kTinKey, *tin);
    } else if (*b != build) {
      throw usageError(
          path.string() + " was built from another TIN or other options than " + inputs[0].string(),
          "merge only shards of one job");
    }
    for (const auto& key : in->keys()) {
      if (key.rfind("tiles/", 0) != 0) continue;
      const auto bytes = in->get(key);
      if (const auto there = stage->get(key)) {
        if (*there != *bytes) throw usageError("tile " + key + " differs between the shards");
        continue;
      }
      stage->put(key, *bytes);
    }
  }
  const auto records = storeRecords(*stage);
  // Every refined tile must have children from some shard.
  const auto b = nlohmann::json::parse(build);
  const double tolerance = b["options"]["tolerance"].get<double>();
  const int maxZoom = b["options"]["maxZoom"].get<int>();
  std::map<TileId, bool> present;
  for (const auto& r : records) present[r.id] = true;
  for (const auto& r : records) {
    if (!(r.error > tolerance && r.id.z < maxZoom)) continue;
    bool any = false;
    for (int c = 0; c < 4; ++c) any = any || present.contains(r.id.child(c));
    if (!any) {
      throw usageError(
          "tile " + r.id.name() + " is refined but none of its children is in the shards",
          "add the shard of subtree " + r.id.child(0).name() + " (and its siblings)");
    }
  }
  finish(*stage, output, records, build);
  if (stagePath != output) fs::remove(stagePath);
  TileJobSummary summary = summarize(records, build);
  summary.reused = records.size();
  return summary;
}

StoreInfo describeTileStore(const fs::path& path) {
  auto st = store::openStoreForReading(path);
  StoreInfo info;
  if (auto b = st->get(kBuildKey)) info.build = *b;
  info.complete = st->contains("tileset.json");
  info.summary = summarize(storeRecords(*st), info.build);
  return info;
}

}  // namespace tinsmith::ingest
