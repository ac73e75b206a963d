#include "ingest/tiles/tile_job.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "core/base/error.hpp"
#include "core/tiles/pyramid_build.hpp"
#include "core/tiles/tileset_json.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/terrain_job.hpp"
#include "ingest/tiles/tile_surface_bytes.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::ingest {

namespace fs = std::filesystem;
using tiles::TileId;
using tiles::TileRecord;

namespace {

constexpr const char* kBuildKey = "tinsmith/build.json";
/// A shard's part of the pyramid: {"subtree": "Z/X/Y"} or {"untilZoom": Z}.
/// Only shard stores hold it; merge reads it to know which tiles a shard
/// answers for (a refined tile's child missing from its shard is empty).
constexpr const char* kShardKey = "tinsmith/shard.json";
/// A shard that finished: {"tiles": N, "crc32": {key: CRC-32 of each tile},
/// "surfaces": {key: CRC-32 of each zoom-K surface}}, put in the stage just
/// before it takes the output's name. A killed or running shard's stage
/// holds kShardKey but not this, and merge refuses it. A shard holds no
/// tile above the mosaic zoom K: it hands over the surfaces of its zoom-K
/// tiles (tileSurfaceKey), the merge builds the top from them.
constexpr const char* kShardFinishedKey = "tinsmith/shard-finished.json";
static_assert(std::string_view(kBuildKey) == store::kStoreMarkerKey);

/// What the tiles are a function of (and nothing else: no subtree, no
/// threads, no time), so shards and resumed runs can be checked against it.
std::string buildRecord(const TinIdentity& identity, const std::string& crs,
                        const std::string& tinName, const TileJobOptions& o,
                        const tiles::Tiler* tiler, const tiles::ContentOptions& content) {
  nlohmann::ordered_json j;
  j["format"] = kTileBuildFormat;
  j["tin"] = {{"name", fs::path(tinName).filename().string()},
              {"crc32", identity.crc32},
              {"vertices", identity.vertices},
              {"triangles", identity.triangles},
              {"crs", crs}};
  j["options"] = {{"tolerance", o.tiler.tolerance},
                  {"maxTriangles", o.tiler.maxTriangles},
                  {"maxZoom", tiler ? tiler->maxZoom() : 0},
                  {"lambdaFactor", o.tiler.lambdaFactor},
                  {"compression", compressionName(o.compression)},
                  {"frame", contentFrameName(o.frame)},
                  {"geoid", o.geoid}};
  // Only a job with Cesium terrain says so: a 3D Tiles store's record is
  // what it was before there were schemes (its --resume and merge hold).
  if (o.scheme != TileScheme::Tiles3D) {
    j["options"]["scheme"] = tileSchemeName(o.scheme);
    j["options"]["attribution"] = o.attribution;
  }
  if (tiler) {
    j["pyramid"] = {{"origin", {tiler->geometry().origin().x, tiler->geometry().origin().y}},
                    {"size", tiler->geometry().size()},
                    {"finestZoom", tiler->finestZoom()},
                    {"levelsPerTile", tiler->levelsPerTile()},
                    {"mosaicZoom", tiler->mosaicZoom()}};
  }
  if (tiler && o.frame == tiles::ContentFrame::Local) {
    const auto& g = content.localOrigin;
    j["pyramid"]["enuOrigin"] = {g.lon, g.lat, g.height};
  }
  return j.dump(2) + "\n";
}

/// Why a store's build record is not `wanted`, for an error that follows
/// "was built ": another tinsmith's tiles, or what differs of the TIN, the
/// options and the pyramid (each with its value in `storedName` and in
/// `wantedName`).
std::string buildDifference(const std::string& stored, const std::string& wanted,
                            const std::string& storedName, const std::string& wantedName) {
  const auto there = nlohmann::json::parse(stored, nullptr, false);
  const auto here = nlohmann::json::parse(wanted, nullptr, false);
  if (!there.is_object()) return "with a build record this tinsmith cannot read";
  auto value = [](const nlohmann::json& j, const char* key) {
    const auto it = j.find(key);
    return it == j.end()     ? std::string("none")
           : it->is_string() ? it->get<std::string>()
                             : it->dump();
  };
  if (there.value("format", "") != here.value("format", ""))
    return "by another version of tinsmith (its tiles are " + value(there, "format") +
           ", this tinsmith makes " + value(here, "format") + ")";
  auto differences = [&](const char* section) {
    std::string out;
    const auto a = there.value(section, nlohmann::json::object());
    const auto b = here.value(section, nlohmann::json::object());
    std::set<std::string> keys;
    for (const auto& [k, v] : a.items()) keys.insert(k);
    for (const auto& [k, v] : b.items()) keys.insert(k);
    for (const auto& k : keys) {
      const std::string va = value(a, k.c_str()), vb = value(b, k.c_str());
      if (va != vb)
        out += (out.empty() ? "" : "; ") + k + " " + va + " " + storedName + ", " + vb + " " +
               wantedName;
    }
    return out;
  };
  std::string out;
  for (const auto& [section, says] :
       {std::pair{"tin", "from another TIN"}, std::pair{"options", "with other options"},
        std::pair{"pyramid", "with another pyramid"}}) {
    if (const std::string d = differences(section); !d.empty())
      out += (out.empty() ? "" : ", and ") + std::string(says) + " (" + d + ")";
  }
  return out.empty() ? "from another TIN or other options" : out;
}

/// The shard record of a run: empty for a whole pyramid.
std::string shardRecord(const TileJobOptions& o) {
  nlohmann::ordered_json j;
  if (o.subtree) {
    j["subtree"] = o.subtree->name();
  } else if (o.untilZoom) {
    j["untilZoom"] = *o.untilZoom;
  } else {
    return {};
  }
  return j.dump() + "\n";
}

/// The canonical order of a finished store's keys: the build record, the
/// TIN (when the stage holds it: a shard below the root does not) and a
/// shard's record, the tiles in `records` (already in rowMajorLess order),
/// a shard's zoom-K surfaces, then the tileset files.
std::vector<std::string> canonicalKeys(const store::TileStore& stage,
                                       const std::vector<TileRecord>& records,
                                       std::vector<std::string> tilesetKeys, bool shard = false,
                                       const std::vector<std::string>& terrainKeys = {},
                                       const std::vector<std::string>& surfaceKeys = {}) {
  std::vector<std::string> out{kBuildKey};
  for (auto& key : store::storedTinKeys(stage)) out.push_back(std::move(key));
  if (shard) out.insert(out.end(), {kShardKey, kShardFinishedKey});
  for (const auto& r : records) out.push_back(tiles::tileContentKey(r.id));
  out.insert(out.end(), surfaceKeys.begin(), surfaceKeys.end());
  std::sort(tilesetKeys.begin(), tilesetKeys.end());
  out.insert(out.end(), tilesetKeys.begin(), tilesetKeys.end());
  out.insert(out.end(), terrainKeys.begin(), terrainKeys.end());
  return out;
}

std::string tilesetExtras(const std::string& build) {
  const auto b = nlohmann::json::parse(build);
  nlohmann::ordered_json e;
  e["tinsmith"] = {{"crs", b["tin"]["crs"]},
                   {"tolerance", b["options"]["tolerance"]},
                   {"finestZoom", b["pyramid"]["finestZoom"]}};
  if (b["options"].contains("scheme")) e["tinsmith"]["terrain"] = "terrain/layer.json";
  if (b["pyramid"].contains("enuOrigin")) e["tinsmith"]["enuOrigin"] = b["pyramid"]["enuOrigin"];
  return e.dump();
}

TileJobSummary summarize(const std::vector<TileRecord>& records, const std::string& build) {
  TileJobSummary s;
  const auto b = nlohmann::json::parse(build, nullptr, false);
  const double tolerance = b.is_discarded() ? 0.0 : b["options"].value("tolerance", 0.0);
  const bool pyramid = !b.is_discarded() && b.contains("pyramid");
  s.finestZoom = pyramid ? b["pyramid"].value("finestZoom", 0) : 0;
  s.levelsPerTile = pyramid ? b["pyramid"].value("levelsPerTile", 0) : 0;
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
    if (r.error > z.tolerance) {
      ++z.overTolerance;
      s.missed.push_back({r.id, r.error, z.tolerance, r.reachableError});
    }
    s.bytes += r.bytes;
  }
  for (auto& [z, summary] : zooms) s.zooms.push_back(summary);
  s.tiles = records.size();
  return s;
}

/// The record a stored tile carries, checked against its key.
TileRecord recordOfTile(const std::string& key, const std::string& bytes, const fs::path& store) {
  const auto record = tiles::recordFromGlb(bytes);
  if (!record) {
    throw inputError("tile " + key + " in " + store.string() + " is not a tinsmith tile", {},
                     "rebuild the store with tinsmith tile");
  }
  if (tiles::tileContentKey(record->id) != key) {
    throw inputError("tile " + key + " in " + store.string() + " says it is " + record->id.name());
  }
  TileRecord r = *record;
  r.bytes = bytes.size();
  return r;
}

void sortRecords(std::vector<TileRecord>& records) {
  std::sort(records.begin(), records.end(), [](const TileRecord& a, const TileRecord& b) {
    return tiles::rowMajorLess(a.id, b.id);
  });
}

/// Records of every tile in a store, from the tiles themselves.
std::vector<TileRecord> storeRecords(const store::TileStore& st) {
  std::vector<TileRecord> records;
  for (const auto& key : st.keys()) {
    if (key.rfind("tiles/", 0) != 0) continue;
    if (const auto bytes = st.get(key)) records.push_back(recordOfTile(key, *bytes, st.path()));
  }
  sortRecords(records);
  return records;
}

/// The path a store is named by: without trailing '/', and with "." and
/// ".." resolved, so that its staging sibling and its folder are known.
fs::path storePathFor(const fs::path& given) {
  fs::path p = given;
  while (!p.has_filename() && p.has_relative_path()) p = p.parent_path();
  if (p.filename() == "." || p.filename() == "..") {
    p = fs::absolute(p).lexically_normal();
    while (!p.has_filename() && p.has_relative_path()) p = p.parent_path();
  }
  if (p.empty() || !p.has_filename())
    throw usageError("'" + given.string() + "' cannot be a tile store",
                     "give an output path such as out/site.3dtiles or out/site");
  return p;
}

/// Where a store is built before it takes its name: "X.partial.3dtiles" for
/// an archive X.3dtiles, the folder "X.partial" for a folder X.
fs::path stagingPath(const fs::path& output) {
  fs::path stage = output;
  if (store::storeKindFor(output) == store::StoreKind::Directory) {
    stage += ".partial";
  } else {
    stage.replace_extension(".partial.3dtiles");
  }
  return stage;
}

bool samePath(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::equivalent(a, b, ec)) return true;
  return fs::absolute(a).lexically_normal() == fs::absolute(b).lexically_normal();
}

/// Gives the finished stage the output's name: an archive is written out
/// in `keys` order and the stage removed; a folder is moved into place.
/// Either way the output is replaced atomically.
void publish(std::unique_ptr<store::TileStore>& stage, const fs::path& stagePath,
             const fs::path& output, const std::vector<std::string>& keys) {
  if (store::storeKindFor(output) == store::StoreKind::Archive) {
    store::writeStore(*stage, keys, output);
    stage.reset();
    std::error_code ec;
    fs::remove(stagePath, ec);
  } else {
    stage.reset();
    store::moveStore(stagePath, output);
  }
}

/// Writes the tileset files from the records into the stage and publishes
/// it as the finished store.
void finish(std::unique_ptr<store::TileStore>& stage, const fs::path& stagePath,
            const fs::path& output, const std::vector<TileRecord>& records,
            const std::string& build, int storeUntilZoom = 1 << 20,
            const std::vector<std::string>& terrainKeys = {}) {
  std::vector<std::string> tilesetKeys;
  if (!records.empty()) {  // a job of Cesium terrain alone has no tileset
    tiles::TilesetOptions tileset;
    tileset.extras = tilesetExtras(build);
    for (const auto& [key, json] : tiles::tilesetFiles(records, tileset)) {
      stage->put(key, json);
      tilesetKeys.push_back(key);
    }
  }
  std::vector<TileRecord> stored;
  for (const auto& r : records)
    if (r.id.z < storeUntilZoom) stored.push_back(r);
  publish(stage, stagePath, output, canonicalKeys(*stage, stored, tilesetKeys, false, terrainKeys));
}

/// --resume: a store this run may take tiles from (its staging store or the
/// finished output) must have been built from the same TIN and options (a
/// tile is a function of those and its id), and for a shard as the same
/// shard (a shard's store holds its part only). Throws usageError naming it
/// otherwise; nullptr when nothing is there.
std::unique_ptr<store::TileStore> resumableStore(const fs::path& path, const std::string& build,
                                                 const std::string& shard) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return nullptr;
  auto st = store::openStoreForReading(path);
  const auto previousBuild = st->get(kBuildKey);
  if (!previousBuild) return nullptr;  // an empty store (a run stopped at its start)
  if (*previousBuild != build)
    throw usageError("the store " + path.string() + " was built " +
                         buildDifference(*previousBuild, build, "in it", "in this run"),
                     "run without --resume to start over, or with the TIN and options it was "
                     "built with");
  if (!shard.empty() && st->get(kShardKey).value_or("") != shard)
    throw usageError("the store " + path.string() + " was built as another shard",
                     "resume with the --subtree / --until-zoom it was built with");
  return st;
}

/// What a shard's store (it holds kShardKey) finished with: the CRC-32 of
/// each tile, by key — or why it is not a finished one: a stage its run left
/// (killed, failed or still running), or a store that lost tiles.
struct ShardFinish {
  std::optional<std::string> unfinished;
  std::map<std::string, std::uint32_t> tileCrcs;
  /// The CRC-32 of each zoom-K surface it hands over, by key; nullopt for a
  /// shard of an older tinsmith, which handed none (and held the top).
  std::optional<std::map<std::string, std::uint32_t>> surfaceCrcs;
};
ShardFinish shardFinish(const store::TileStore& in) {
  const auto finished = in.get(kShardFinishedKey);
  const auto unfinished = [](std::string why) { return ShardFinish{std::move(why), {}, {}}; };
  if (!finished)
    return unfinished("the shard did not finish (no " + std::string(kShardFinishedKey) +
                      "): it is the stage of a run that was killed, failed or is still running");
  const auto j = nlohmann::json::parse(*finished, nullptr, false);
  const auto isCrcs = [](const nlohmann::json& v) {
    return v.is_object() && std::all_of(v.begin(), v.end(), [](const nlohmann::json& c) {
             return c.is_number_unsigned() && c.get<std::uint64_t>() <= 0xffffffffU;
           });
  };
  if (!j.is_object() || !j.contains("tiles") || !j["tiles"].is_number_unsigned() ||
      !j.contains("crc32") || !isCrcs(j["crc32"]) ||
      j["crc32"].size() != j["tiles"].get<std::size_t>() ||
      (j.contains("surfaces") && !isCrcs(j["surfaces"])))
    return unfinished("its " + std::string(kShardFinishedKey) + " is not one tinsmith writes");
  ShardFinish out;
  for (const auto& [key, crc] : j["crc32"].items())
    out.tileCrcs.emplace(key, crc.get<std::uint32_t>());
  if (j.contains("surfaces")) {
    out.surfaceCrcs.emplace();
    for (const auto& [key, crc] : j["surfaces"].items())
      out.surfaceCrcs->emplace(key, crc.get<std::uint32_t>());
  }
  // Every tile and surface the store holds is one its shard finished with.
  const auto listed = [](const std::map<std::string, std::uint32_t>* crcs, const char* prefix,
                         const char* what,
                         const std::vector<std::string>& keys) -> std::optional<std::string> {
    std::size_t n = 0;
    for (const auto& key : keys) {
      if (key.rfind(prefix, 0) != 0) continue;
      ++n;
      if (!crcs || !crcs->contains(key))
        return "it holds the " + std::string(what) + " " + key +
               ", which its shard did not finish with";
    }
    const std::size_t wanted = crcs ? crcs->size() : 0;
    if (n != wanted)
      return "it holds " + std::to_string(n) + " of the " + std::to_string(wanted) + " " + what +
             "s its shard finished with";
    return std::nullopt;
  };
  const auto keys = in.keys();
  if (auto why = listed(&out.tileCrcs, "tiles/", "tile", keys)) return unfinished(std::move(*why));
  if (auto why = listed(out.surfaceCrcs ? &*out.surfaceCrcs : nullptr, "tinsmith/surfaces/",
                        "tile surface", keys))
    return unfinished(std::move(*why));
  return out;
}

}  // namespace

std::optional<encode::Compression> parseCompression(std::string_view name) {
  if (name == "draco") return encode::Compression::Draco;
  if (name == "none") return encode::Compression::None;
  return std::nullopt;
}

std::optional<tiles::ContentFrame> parseContentFrame(std::string_view name) {
  if (name == "ecef") return tiles::ContentFrame::Ecef;
  if (name == "local") return tiles::ContentFrame::Local;
  return std::nullopt;
}

bool isKnownGeoid(std::string_view name) {
  return name.empty() || name == "egm96";
}

std::string_view compressionName(encode::Compression compression) {
  return compression == encode::Compression::Draco ? "draco" : "none";
}

std::string_view contentFrameName(tiles::ContentFrame frame) {
  return frame == tiles::ContentFrame::Ecef ? "ecef" : "local";
}

std::optional<TileScheme> parseTileScheme(std::string_view name) {
  if (name == "3d-tiles") return TileScheme::Tiles3D;
  if (name == "quantized-mesh") return TileScheme::QuantizedMesh;
  if (name == "both") return TileScheme::Both;
  return std::nullopt;
}

std::string_view tileSchemeName(TileScheme scheme) {
  switch (scheme) {
    case TileScheme::Tiles3D:
      return "3d-tiles";
    case TileScheme::QuantizedMesh:
      return "quantized-mesh";
    case TileScheme::Both:
      return "both";
  }
  return "3d-tiles";
}

void checkTileJobOptions(const TileJobOptions& o) {
  const auto& t = o.tiler;
  if (!(t.tolerance > 0) || !std::isfinite(t.tolerance)) {
    throw usageError("the tile tolerance must be a positive number of metres (got " +
                         std::to_string(t.tolerance) + ")",
                     "set [tiles] tolerance or --tolerance to e.g. 1");
  }
  if (t.maxTriangles < 64) {
    throw usageError(
        "max triangles must be at least 64 (got " + std::to_string(t.maxTriangles) + ")",
        "set [tiles] max_triangles or --max-triangles to e.g. 32768");
  }
  if (t.maxZoom && (*t.maxZoom < 0 || *t.maxZoom > 30)) {
    throw usageError("max zoom must be 0 to 30 (got " + std::to_string(*t.maxZoom) + ")",
                     "set [tiles] max_zoom or --max-zoom, or leave it out");
  }
  if (!(t.lambdaFactor > 0) || !std::isfinite(t.lambdaFactor)) {
    throw usageError(
        "lambda must be a positive multiple of λ_d (got " + std::to_string(t.lambdaFactor) + ")",
        "set [tiles] lambda or --lambda to e.g. 0.01");
  }
  if (!isKnownGeoid(o.geoid)) {
    throw usageError("unknown geoid '" + o.geoid + "'",
                     "use geoid \"egm96\" or leave it out (ellipsoidal heights)");
  }
  if (t.plannedFinestZoom && (*t.plannedFinestZoom < 0 || *t.plannedFinestZoom > 30))
    throw usageError(
        "--finest-zoom must be 0 to 30 (got " + std::to_string(*t.plannedFinestZoom) + ")",
        "give the finestZoom of the job's plan.json, or leave it out");
  if (o.threads < 0) throw usageError("--threads must be 0 (all cores) or more");
  if (o.untilZoom && *o.untilZoom < 1) throw usageError("--until-zoom must be 1 or more");
  if (o.uncheckedAncestors && !o.subtree)
    throw usageError("--unchecked-ancestors goes with --subtree",
                     "it is for shard arrays (tinsmith slurm), whose merge drops what is not in "
                     "the pyramid");
  if (o.subtree && o.untilZoom)
    throw usageError("--subtree and --until-zoom make different shards: give one");
  if (o.writePlan && (!o.untilZoom || o.plan))
    throw usageError("--write-plan goes with --until-zoom, without --plan",
                     "the top of a sharded job writes the plan its subtrees take");
  if (o.storeUntilZoom && *o.storeUntilZoom < 1)
    throw usageError("--store-until-zoom must be 1 or more (the root is always stored)");
  if (o.storeUntilZoom && (o.subtree || o.untilZoom))
    throw usageError("--store-until-zoom is for a whole pyramid, not a shard",
                     "leave out --subtree and --until-zoom");
  if (writesTerrain(o.scheme)) (void)tiles::terrainLevelFor(t.tolerance);
  if (writesTerrain(o.scheme) && (o.subtree || o.untilZoom || o.storeUntilZoom))
    throw usageError("Cesium terrain (--scheme " + std::string(tileSchemeName(o.scheme)) +
                         ") is built whole: no --subtree, --until-zoom or --store-until-zoom",
                     "shard the 3D Tiles with --scheme 3d-tiles");
}

encode::Geodetic pyramidCentre(const tiles::PyramidGeometry& pyramid,
                               const tiles::GeoReference& geo) {
  const Point2 o = pyramid.origin();
  const double half = 0.5 * pyramid.size();
  const Point3 centre{o.x + half, o.y + half, 0.0};
  encode::Geodetic g;
  geo.toGeodetic({&centre, 1}, {&g, 1});
  return g;
}

namespace {

/// The error for a subtree (or shard zoom) above the mosaic zoom K, `what`
/// naming it: the tiles above K are fitted to the mosaic of all of zoom K's.
[[noreturn]] void refuseAboveMosaicZoom(const std::string& what, int mosaicZoom) {
  const std::string k = std::to_string(mosaicZoom);
  throw usageError(what + " lies above zoom " + k +
                       ", the mosaic zoom of this TIN (over 2^18 vertices): the tiles above it "
                       "are fitted to the mosaic of all of zoom " +
                       k + "'s tiles, and are built only as the whole top",
                   "shard at zoom " + k + " or below (tinsmith slurm --shard-zoom " + k +
                       " or more; tinsmith tile --subtree of zoom " + k + " or more)");
}

}  // namespace

TileJobSummary runTileJob(const TinData& tin, const std::string& tinName, const fs::path& output,
                          const TileJobOptions& options, const Progress* progress) {
  checkTileJobOptions(options);
  const auto start = std::chrono::steady_clock::now();
  requireTinCrs(tin.crs, tinName);
  // Heights and tolerances are metres: a TIN in a CRS of feet is refused.
  checkProjectCrs(tin.crs, "the CRS of " + tinName);
  // Both frames place the tiles through the TIN's CRS (the local frame's
  // east-north-up axes stand at the pyramid's centre); a CRS PROJ cannot use
  // fails here, before the planning.
  const ProjGeoReference geo(tin.crs, options.geoid);
  const bool tiles3d = writesTiles3D(options.scheme);
  tiles::TilerOptions tilerOptions = options.tiler;
  tilerOptions.threads = options.threads;
  tilerOptions.geo = &geo;  // chord sag as the CRS bends it (chordSagRadius)
  // The TIN as the build record names it: the file's bytes (written with
  // the root), or the plan's whole TIN, of which `tin` is a part.
  const TileId root = options.subtree.value_or(TileId{});
  const bool holdsRoot = root.z == 0;
  std::string tinBytes;
  TinIdentity identity;
  const auto encodeWhole = [&] {
    tinBytes = encodeTin(tin);
    identity = {crc32(tinBytes), tin.vertices.size(), tin.triangles.size()};
  };
  if (options.partOf) {
    if (!options.plan || !options.uncheckedAncestors || holdsRoot)
      throw usageError("part of a TIN is tiled only as a subtree below the root, with the job's "
                       "plan and --unchecked-ancestors");
    identity = *options.partOf;
  } else if (options.plan || !tiles3d) {
    encodeWhole();
  }
  if (options.plan) {
    if (identity != options.plan->tin)
      throw inputError("the tiling plan was made for another TIN (CRC-32 " +
                           std::to_string(options.plan->tin.crc32) + ", this one's is " +
                           std::to_string(identity.crc32) + ")",
                       fileLocation(tinName), "plan the job again for this TIN");
    requirePlannedOptions(*options.plan, options.tiler, "of this job");
    tilerOptions.plan = std::shared_ptr<const tiles::TilerPlan>(options.plan, &options.plan->tiler);
    if (options.partOf) tilerOptions.region = options.plan->tiler.geometry.bounds(root);
  }
  std::optional<tiles::Tiler> tiler;
  tiles::ContentOptions content;
  content.compression = options.compression;
  content.frame = options.frame;
  content.geo = &geo;
  if (tiles3d) {
    reportProgress(progress, "tiles.plan", "", 0, 0);
    tiler.emplace(tin, tilerOptions);
    reportProgress(progress, "tiles.plan", "", 1, 1);
    // Encoded after the planning fit, in the memory it has given back: the
    // TIN's bytes and the fit's working data are not held at once.
    if (!options.partOf && !options.plan) encodeWhole();
    content.localOrigin = pyramidCentre(tiler->geometry(), geo);
    // Everything that can refuse the run is checked before the output is touched.
    // Above the mosaic zoom only the whole top is built (buildPyramid).
    const int mosaicZoom = tiler->mosaicZoom();
    if (root.z > 0 && root.z < mosaicZoom)
      refuseAboveMosaicZoom("the subtree " + root.name(), mosaicZoom);
    if (options.untilZoom && *options.untilZoom < mosaicZoom)
      refuseAboveMosaicZoom(
          "--until-zoom " + std::to_string(*options.untilZoom) + " leaves subtrees that",
          mosaicZoom);
    if (options.uncheckedAncestors) {
      if (!tiler->geometry().inside(root))
        throw usageError("tile " + root.name() + " is outside the pyramid");
    } else if (options.subtreeMayBeEmpty && tiler->geometry().inside(root)) {
      if (auto why = tiles::whyNotInPyramid(*tiler, content, root)) {
        TileJobSummary empty;
        empty.notInPyramid = "tile " + root.name() + " is not in the pyramid: " + *why;
        return empty;
      }
    } else {
      tiles::requireInPyramid(*tiler, content, root);
    }
    if (options.writePlan) {
      const int cornerZoom = std::min(*options.untilZoom + 4, tiles::kMaxCornerZoom);
      writeTilingPlan(*options.writePlan,
                      makeTilingPlan(*tiler, tilerOptions, cornerZoom, identity));
    }
  }
  std::optional<tiles::GeographicTin> geographic;  // Cesium terrain's working frame
  if (writesTerrain(options.scheme)) geographic = tiles::toGeographicTin(tin, geo);
  const std::string build =
      buildRecord(identity, tin.crs, tinName, options, tiler ? &*tiler : nullptr, content);
  const std::string shard = shardRecord(options);
  const fs::path out = storePathFor(output);
  const fs::path stagePath = stagingPath(out);
  store::requireReplaceable(out);
  store::requireReplaceable(stagePath);
  std::unique_ptr<store::TileStore> previous;  // the finished output's tiles, for --resume
  // A finished shard's tiles' CRC-32: a tile whose bytes are not those is
  // built again, not carried on under a new CRC.
  std::map<std::string, std::uint32_t> previousCrcs, previousSurfaceCrcs;
  if (options.resume) {
    (void)resumableStore(stagePath, build, shard);
    previous = resumableStore(out, build, shard);
    if (previous && previous->contains(kShardKey)) {
      ShardFinish finished = shardFinish(*previous);
      previousCrcs = std::move(finished.tileCrcs);
      if (finished.surfaceCrcs) previousSurfaceCrcs = std::move(*finished.surfaceCrcs);
    }
  }
  store::removeStaleTemps(out);
  store::removeStaleTemps(stagePath);

  auto stage = store::openStoreForWriting(stagePath, options.resume);
  if (options.resume && holdsRoot && store::holdsEmptyTin(*stage))
    throw usageError("the stage '" + stagePath.string() +
                         "' holds an empty TIN (an older tinsmith stored a TIN over 10^9 bytes "
                         "as nothing)",
                     "run again without --resume");
  stage->put(kBuildKey, build);
  // The TIN goes with the pyramid's root (the whole run, or the top shard):
  // a subtree shard would copy the whole TIN for its part of the tiles.
  if (holdsRoot && !store::holdsTin(*stage)) store::putTin(*stage, tinBytes, options.tinPieceBytes);
  std::string().swap(tinBytes);  // stored: not held through the tiles (the TIN's size again)
  if (!shard.empty()) {
    stage->put(kShardKey, shard);
  } else if (store::storeKindFor(out) == store::StoreKind::Directory) {
    // A whole run resumed from a shard's tiles is no shard (an archive's
    // canonical keys leave the record out).
    std::error_code ec;
    fs::remove(stagePath / kShardKey, ec);
  }

  // The tiles above the mosaic zoom are always stored: they are fitted to
  // the mosaic of zoom K's tiles, which a rebuild on demand has not got.
  const int mosaicZoom = tiler ? tiler->mosaicZoom() : 0;
  const int storeUntilZoom = std::max(options.storeUntilZoom.value_or(1 << 20), mosaicZoom);
  // A shard leaves the tiles above the mosaic zoom to the merge and hands
  // it the surface of each zoom-K tile it holds, put just before the tile.
  const bool handsSurfaces = !shard.empty() && mosaicZoom > 0;
  std::map<TileId, std::string> surfaces;  // encoded on the workers, not yet put
  std::mutex surfacesMutex;
  tiles::PyramidSummary walked;
  if (tiles3d) {
    tiles::PyramidCallbacks callbacks;
    if (options.resume) {
      // The finished output's copy of `key`; a shard's only when it
      // finished with it and these bytes (none of one that did not finish).
      const bool previousIsShard = previous && previous->contains(kShardKey);
      const auto fromPrevious = [&, previousIsShard](const std::string& key, const auto& crcs) {
        auto bytes = previous ? previous->get(key) : std::nullopt;
        if (const auto crc = crcs.find(key);
            bytes && previousIsShard && (crc == crcs.end() || crc32(*bytes) != crc->second))
          bytes.reset();
        return bytes;
      };
      callbacks.existing = [&, fromPrevious](const TileId& id) -> std::optional<TileRecord> {
        // A shard's zoom-K tile is built again without its surface.
        if (const std::string key = tileSurfaceKey(id);
            handsSurfaces && id.z == mosaicZoom && !stage->contains(key)) {
          const auto bytes = fromPrevious(key, previousSurfaceCrcs);
          if (!bytes) return std::nullopt;
          stage->put(key, *bytes);
        }
        const std::string key = tiles::tileContentKey(id);
        if (const auto bytes = stage->get(key)) return recordOfTile(key, *bytes, stagePath);
        const auto bytes = fromPrevious(key, previousCrcs);
        if (!bytes) return std::nullopt;
        TileRecord record = recordOfTile(key, *bytes, out);
        stage->put(key, *bytes);  // the stage becomes the whole new store
        return record;
      };
    }
    if (handsSurfaces) {
      callbacks.mosaicSurface = [&](const tiles::TileSurface& s) {
        if (s.empty()) return;
        std::string bytes = encodeTileSurface(s);
        std::lock_guard lock(surfacesMutex);
        surfaces[s.id] = std::move(bytes);
      };
    }
    callbacks.emit = [&](const tiles::TileContent& c) {
      const TileId& id = c.record.id;
      if (handsSurfaces && id.z == mosaicZoom) {
        std::string bytes;
        {
          std::lock_guard lock(surfacesMutex);
          const auto it = surfaces.find(id);
          if (it == surfaces.end())
            throw internalError("tile " + id.name() + " came without its surface");
          bytes = std::move(it->second);
          surfaces.erase(it);
        }
        stage->put(tileSurfaceKey(id), bytes);
      }
      if (id.z < storeUntilZoom) stage->put(tiles::tileContentKey(id), c.glb);
    };
    callbacks.progress = [&](int z, std::size_t done, std::size_t total) {
      reportProgress(progress, "tiles.zoom", "zoom " + std::to_string(z), done, total);
    };
    walked = tiles::buildPyramid(*tiler, content, root, options.threads, callbacks,
                                 options.untilZoom.value_or(1 << 20));
  }
  std::optional<TerrainSummary> terrain;
  std::vector<std::string> terrainKeys;
  if (writesTerrain(options.scheme))
    terrain = tileTerrain(*geographic, options, *stage, previous.get(), terrainKeys, progress);
  previous.reset();

  // The walk's records are the stage's tiles: those it built and those a
  // resumed run found.
  const std::vector<TileRecord>& records = walked.records;
  std::size_t surfaceCount = 0;
  if (shard.empty()) {
    finish(stage, stagePath, out, records, build, storeUntilZoom, terrainKeys);
  } else {
    // A shard: no tileset.json of its own; `tinsmith merge` writes it. It
    // finishes with its tiles' count and each one's CRC-32, which the merge
    // checks the bytes it reads against (a shared filesystem's damage).
    // The surfaces, of its zoom-K tiles, too.
    nlohmann::ordered_json crcs = nlohmann::ordered_json::object();
    nlohmann::ordered_json surfaceCrcs = nlohmann::ordered_json::object();
    std::vector<std::string> surfaceKeys;
    const auto crcOf = [&](const std::string& key) {
      const auto bytes = stage->get(key);
      if (!bytes) throw internalError("the shard's " + key + " is not in its stage");
      return crc32(*bytes);
    };
    for (const auto& r : records) {
      const std::string key = tiles::tileContentKey(r.id);
      crcs[key] = crcOf(key);
      if (handsSurfaces && r.id.z == mosaicZoom) {
        surfaceKeys.push_back(tileSurfaceKey(r.id));
        surfaceCrcs[surfaceKeys.back()] = crcOf(surfaceKeys.back());
      }
    }
    nlohmann::ordered_json finished{{"tiles", records.size()}, {"crc32", crcs}};
    if (handsSurfaces) finished["surfaces"] = surfaceCrcs;
    stage->put(kShardFinishedKey, finished.dump() + "\n");
    publish(stage, stagePath, out, canonicalKeys(*stage, records, {}, true, {}, surfaceKeys));
    surfaceCount = surfaceKeys.size();
  }
  TileJobSummary summary = summarize(records, build);
  summary.terrain = std::move(terrain);
  summary.built = walked.built;
  summary.reused = walked.reused;
  summary.dataPoints = tiler ? tiler->dataPointCount() : 0;
  if (handsSurfaces) {
    summary.leftAboveZoom = mosaicZoom;
    summary.surfacesHandedOver = surfaceCount;
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

namespace {

/// Which tiles a merge input answers for: a shard its part (kShardKey), a
/// finished store every tile.
struct ShardCoverage {
  bool shard = false;  ///< false: a finished store, which answers for every tile
  std::optional<TileId> subtree;
  std::optional<int> untilZoom;
  /// A shard's: the CRC-32 of each tile it finished with, by key (a
  /// finished store's tiles are not checked).
  std::map<std::string, std::uint32_t> tileCrcs;
  /// A shard's: those of the zoom-K surfaces it hands over (nullopt: none,
  /// a shard of an older tinsmith).
  std::optional<std::map<std::string, std::uint32_t>> surfaceCrcs;

  [[nodiscard]] bool covers(const TileId& id) const {
    if (untilZoom) return id.z < *untilZoom;
    if (!subtree) return true;
    const int dz = id.z - subtree->z;
    return dz >= 0 && (id.x >> dz) == subtree->x && (id.y >> dz) == subtree->y;
  }
};

ShardCoverage coverageOf(const store::TileStore& in) {
  const auto record = in.get(kShardKey);
  if (!record) {
    if (in.contains("tileset.json")) return {};
    throw inputError("the store is neither a shard (no " + std::string(kShardKey) +
                         ") nor finished (no tileset.json)",
                     fileLocation(in.path().string()),
                     "build the shard again with tinsmith tile --subtree or --until-zoom");
  }
  ShardFinish finish = shardFinish(in);
  if (finish.unfinished)
    throw inputError(*finish.unfinished, fileLocation(in.path().string()),
                     "run that shard again (tinsmith slurm … --resume --submit, or its tinsmith "
                     "tile command with --resume) and merge its finished store");
  const auto j = nlohmann::json::parse(*record, nullptr, false);
  ShardCoverage c;
  c.shard = true;
  c.tileCrcs = std::move(finish.tileCrcs);
  c.surfaceCrcs = std::move(finish.surfaceCrcs);
  if (j.is_object() && j.contains("subtree") && j["subtree"].is_string()) {
    c.subtree = tiles::parseTileId(j["subtree"].get<std::string>(), kShardKey);
  } else if (j.is_object() && j.contains("untilZoom") && j["untilZoom"].is_number_integer()) {
    c.untilZoom = j["untilZoom"].get<int>();
  } else {
    throw inputError("the shard record " + std::string(kShardKey) + " is not one tinsmith writes",
                     fileLocation(in.path().string()), "build the shard again");
  }
  return c;
}

/// What the merge of a job whose inputs are all shards builds the tiles
/// above the mosaic zoom K from, as one run builds them
/// (tiles::buildMosaicTop): the tiling options, pyramid and content the
/// build record names, and every zoom-K tile's surface the shards hand over.
struct ShardsTop {
  tiles::PyramidFrame frame;
  std::string geoid;
  tiles::ContentOptions content;          ///< without its geo
  std::vector<tiles::TileSurface> zoomK;  ///< row by row, empty where no shard holds one
};

/// Reads and checks a ShardsTop, before the merge touches its output.
/// Throws inputError naming the shard when a surface is missing, damaged or
/// not one tinsmith writes, and usageError when no shard answers for a
/// zoom-K tile.
ShardsTop readShardsTop(const std::vector<std::unique_ptr<store::TileStore>>& shards,
                        const std::vector<ShardCoverage>& coverage, const std::string& buildText) {
  ShardsTop top;
  tiles::PyramidFrame& frame = top.frame;
  std::string compression, contentFrame;
  try {
    const auto b = nlohmann::json::parse(buildText);
    const auto& o = b.at("options");
    const auto& p = b.at("pyramid");
    frame.options.tolerance = o.at("tolerance").get<double>();
    frame.options.maxTriangles = o.at("maxTriangles").get<std::size_t>();
    frame.options.lambdaFactor = o.at("lambdaFactor").get<double>();
    frame.geometry = tiles::PyramidGeometry(
        {p.at("origin").at(0).get<double>(), p.at("origin").at(1).get<double>()},
        p.at("size").get<double>());
    frame.finestZoom = p.at("finestZoom").get<int>();
    frame.maxZoom = o.at("maxZoom").get<int>();
    frame.mosaicZoom = p.at("mosaicZoom").get<int>();
    frame.crs = b.at("tin").at("crs").get<std::string>();
    top.geoid = o.at("geoid").get<std::string>();
    compression = o.at("compression").get<std::string>();
    contentFrame = o.at("frame").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    throw inputError(
        std::string("the shards' build record is not one this tinsmith reads (") + e.what() + ")",
        fileLocation(shards.front()->path().string()), "build the shards again");
  }
  const int k = frame.mosaicZoom;
  const auto parsedCompression = parseCompression(compression);
  const auto parsedFrame = parseContentFrame(contentFrame);
  // K is at most the finest zoom; its 4^K surfaces are made before a shard
  // is read.
  if (k < 1 || k > std::min(frame.finestZoom, 12) || !parsedCompression || !parsedFrame ||
      !isKnownGeoid(top.geoid))
    throw inputError("the shards' build record names mosaic zoom " + std::to_string(k) +
                         " (finest zoom " + std::to_string(frame.finestZoom) + "), compression '" +
                         compression + "', frame '" + contentFrame + "' and geoid '" + top.geoid +
                         "'",
                     fileLocation(shards.front()->path().string()), "build the shards again");
  top.content.compression = *parsedCompression;
  top.content.frame = *parsedFrame;

  // Every zoom-K tile's surface, row by row: from the shards that answer
  // for it (the same bytes in each), empty where they hold none.
  const std::uint32_t side = 1U << k;
  auto& zoomK = top.zoomK;
  zoomK.resize(std::size_t{side} * side);
  for (std::uint32_t y = 0; y < side; ++y) {
    for (std::uint32_t x = 0; x < side; ++x) {
      const TileId id{k, x, y};
      const std::string key = tileSurfaceKey(id);
      bool answered = false;
      std::optional<std::string> bytes;
      for (std::size_t i = 0; i < shards.size(); ++i) {
        if (!coverage[i].covers(id)) continue;
        answered = true;
        const auto where = fileLocation(shards[i]->path().string());
        const auto& crcs = coverage[i].surfaceCrcs;
        if (!crcs)
          throw inputError("it holds no surfaces of its zoom-" + std::to_string(k) +
                               " tiles, of which the merge builds the tiles above them: it was "
                               "built by an older tinsmith",
                           where, "build the shard again with this tinsmith");
        auto here = shards[i]->get(key);
        if (!here) {
          if (shards[i]->contains(tiles::tileContentKey(id)))
            throw inputError("it holds tile " + id.name() + " but not its surface " + key, where,
                             "build the shard again");
          continue;
        }
        if (const auto crc = crcs->find(key); crc == crcs->end() || crc32(*here) != crc->second)
          throw inputError("its tile surface " + key +
                               " is damaged: its bytes are not those its shard finished with "
                               "(CRC-32)",
                           where, "build the shard again, then merge");
        if (bytes && *bytes != *here)
          throw usageError("the surface of tile " + id.name() + " differs between the shards");
        if (!bytes) {
          tiles::TileSurface s = decodeTileSurface(*here, shards[i]->path().string() + " " + key);
          if (s.id != id)
            throw inputError("its " + key + " is the surface of tile " + s.id.name(), where,
                             "build the shard again");
          zoomK[std::size_t{y} * side + x] = std::move(s);
        }
        bytes = std::move(here);
      }
      if (!answered)
        throw usageError("tile " + id.name() + ", of the mosaic zoom " + std::to_string(k) +
                             " whose tiles the top is fitted to, is in none of the shards",
                         "add the shard of subtree " + id.name() + " (or one above it)");
    }
  }

  return top;
}

/// Builds the tiles above the mosaic zoom from `top`; `emit` takes each
/// one, in (z, y, x) order.
void buildShardsTop(ShardsTop top, int threads, const Progress* progress,
                    const std::function<void(const tiles::TileContent&)>& emit) {
  const ProjGeoReference geo(top.frame.crs, top.geoid);
  top.frame.options.geo = &geo;
  top.content.geo = &geo;
  top.content.localOrigin = pyramidCentre(top.frame.geometry, geo);
  tiles::PyramidCallbacks callbacks;
  callbacks.emit = emit;
  callbacks.progress = [&](int z, std::size_t done, std::size_t total) {
    reportProgress(progress, "tiles.zoom", "zoom " + std::to_string(z), done, total);
  };
  (void)tiles::buildMosaicTop(top.frame, std::move(top.zoomK), top.content, threads, callbacks);
}

}  // namespace

bool isFinishedShard(const fs::path& path, bool checkTileBytes) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return false;
  try {
    const auto in = store::openStoreForReading(path);
    if (!in->contains(kShardKey)) return false;
    const ShardFinish finish = shardFinish(*in);
    if (finish.unfinished) return false;
    // A shard of an older tinsmith hands over no zoom-K surfaces, which the
    // merge of a job with a mosaic zoom needs.
    const auto build = nlohmann::json::parse(in->get(kBuildKey).value_or(""), nullptr, false);
    if (!finish.surfaceCrcs && build.is_object() &&
        build.value("/pyramid/mosaicZoom"_json_pointer, 0) > 0)
      return false;
    if (!checkTileBytes) return true;
    // A tile or surface whose bytes are not those the shard finished with (a
    // shared filesystem's damage) would fail the merge.
    const auto intact = [&](const std::map<std::string, std::uint32_t>& crcs) {
      return std::all_of(crcs.begin(), crcs.end(), [&](const auto& kv) {
        const auto bytes = in->get(kv.first);
        return bytes && crc32(*bytes) == kv.second;
      });
    };
    return intact(finish.tileCrcs) && (!finish.surfaceCrcs || intact(*finish.surfaceCrcs));
  } catch (const Error&) {
    return false;
  }
}

TileJobSummary mergeTileStores(const std::vector<fs::path>& inputs, const fs::path& output,
                               int threads, const Progress* progress) {
  if (inputs.empty())
    throw usageError("nothing to merge", "name the shard stores: tinsmith merge A B … -o ALL");
  const fs::path out = storePathFor(output);
  const fs::path stagePath = stagingPath(out);
  // Every check before the output is touched: the inputs are all shards of
  // one job, none of them is the output.
  std::vector<std::unique_ptr<store::TileStore>> shards;
  std::vector<ShardCoverage> coverage;
  std::string build;
  for (const auto& path : inputs) {
    if (samePath(path, out) || samePath(path, stagePath))
      throw usageError("the output " + out.string() + " is also an input (" + path.string() + ")",
                       "write the merged store to a new path");
    auto in = store::openStoreForReading(path);
    const auto b = in->get(kBuildKey);
    if (!b)
      throw inputError(path.string() + " is not a tinsmith tile store (no " + kBuildKey + ")");
    if (build.empty()) {
      build = *b;
    } else if (*b != build) {
      throw usageError(
          path.string() + " was built " +
              buildDifference(*b, build, "in it", "in " + inputs[0].filename().string()) +
              " than " + inputs[0].string(),
          "merge only shards of one job, made by one tinsmith");
    }
    coverage.push_back(coverageOf(*in));
    shards.push_back(std::move(in));
  }
  // The pyramid's root is answered for by some input: the top shard, or a
  // finished store.
  if (std::none_of(coverage.begin(), coverage.end(),
                   [](const ShardCoverage& s) { return s.covers(TileId{}); }))
    throw usageError(
        "none of the stores is the top of the pyramid (the shard that answers for tile "
        "0/0/0 and the tiles above the subtrees, and holds the TIN)",
        "add the top shard, built with tinsmith tile --until-zoom (task 0 of "
        "tinsmith slurm: shards/0.3dtiles)");
  // Over a mosaic zoom, when every input is a shard, the merge builds the
  // tiles above it (a finished store holds them): their surfaces are read
  // and checked here.
  const auto b = nlohmann::json::parse(build);
  // (A store of tinsmith-tiles/4 or older has none: its top was the TIN's.)
  const int mosaicZoom = b.at("pyramid").value("mosaicZoom", 0);
  std::optional<ShardsTop> top;
  if (mosaicZoom > 0 &&
      std::all_of(coverage.begin(), coverage.end(), [](const ShardCoverage& c) { return c.shard; }))
    top = readShardsTop(shards, coverage, build);
  store::requireReplaceable(out);
  store::requireReplaceable(stagePath);
  store::removeStaleTemps(out);
  store::removeStaleTemps(stagePath);

  auto stage = store::openStoreForWriting(stagePath, false);
  std::vector<TileRecord> records;
  std::size_t builtHere = 0;  // the tiles above the mosaic zoom, when the merge builds them
  try {
    stage->put(kBuildKey, build);
    // Every tile of every shard, once (a tile two shards hold must be the
    // same bytes in both), and which shard it is read from — or the merge,
    // which builds the tiles above the mosaic zoom when every input is a
    // shard (a finished store holds them).
    constexpr std::size_t kBuiltHere = SIZE_MAX;
    std::map<std::string, std::size_t> from;
    std::vector<TileRecord> found;
    for (std::size_t i = 0; i < shards.size(); ++i) {
      const auto& in = shards[i];
      if (!store::holdsTin(*stage)) store::copyTin(*in, *stage);  // a piece at a time
      const auto& crcs = coverage[i].tileCrcs;
      for (const auto& key : in->keys()) {
        if (key.rfind("tiles/", 0) != 0) continue;
        const auto bytes = in->get(key);
        if (!bytes) continue;
        if (const auto crc = crcs.find(key); crc != crcs.end() && crc32(*bytes) != crc->second)
          throw inputError("its tile " + key +
                               " is damaged: its bytes are not those its shard finished with "
                               "(CRC-32)",
                           fileLocation(in->path().string()),
                           "build the shard again (tinsmith slurm … --resume --submit "
                           "reruns it, or its tinsmith tile command without --resume), "
                           "then merge");
        if (const auto there = from.find(key); there != from.end()) {
          if (shards[there->second]->get(key) != bytes)
            throw usageError("tile " + key + " differs between the shards");
          continue;
        }
        from.emplace(key, i);
        found.push_back(recordOfTile(key, *bytes, in->path()));
      }
      decltype(coverage[i].tileCrcs)().swap(coverage[i].tileCrcs);  // checked: let go
    }
    if (top) {
      buildShardsTop(std::move(*top), threads, progress, [&](const tiles::TileContent& c) {
        const std::string key = tiles::tileContentKey(c.record.id);
        // A shard of an older tinsmith held the top.
        if (const auto there = from.find(key); there != from.end()) {
          if (shards[there->second]->get(key) != c.glb)
            throw usageError("tile " + key + " of " + shards[there->second]->path().string() +
                             " differs from the one the merge built from the shards' zoom-" +
                             std::to_string(mosaicZoom) + " surfaces");
          return;
        }
        stage->put(key, c.glb);
        from.emplace(key, kBuiltHere);
        TileRecord r = c.record;
        r.bytes = c.glb.size();
        found.push_back(std::move(r));
        ++builtHere;
      });
      top.reset();
    }
    sortRecords(found);
    const double tolerance = b["options"]["tolerance"].get<double>();
    const int maxZoom = b["options"]["maxZoom"].get<int>();
    const int finestZoom = b["pyramid"]["finestZoom"].get<int>();
    // Above the mosaic zoom every tile with terrain refines (Tiler::refines).
    const auto refines = [&](const TileRecord& r) {
      return r.id.z < mosaicZoom ||
             tiles::tileRefines(r.error, r.reachableError, r.id.z, tolerance, finestZoom, maxZoom);
    };
    const auto answered = [&](const TileId& id) {
      return std::any_of(coverage.begin(), coverage.end(),
                         [&](const ShardCoverage& s) { return s.covers(id); });
    };
    // The pyramid: a tile whose parent a shard answers for is in it only
    // under a refined parent. A shard built without its ancestors
    // (--unchecked-ancestors) may hold a subtree that is not; it is left out.
    std::set<TileId> refined;
    for (auto& r : found) {
      if (r.id.z > 0 && answered(r.id.parent()) && !refined.contains(r.id.parent())) continue;
      if (refines(r)) refined.insert(r.id);
      records.push_back(std::move(r));
    }
    // Every child of a refined tile is in the shards, or in the part of one
    // that holds no terrain there (a shard that answers for it found it empty).
    std::set<TileId> present;
    for (const auto& r : records) present.insert(r.id);
    for (const TileId& id : refined) {
      for (int c = 0; c < 4; ++c) {
        const TileId child = id.child(c);
        if (!present.contains(child) && !answered(child))
          throw usageError("tile " + id.name() + " is refined but its child " + child.name() +
                               " is in none of the shards",
                           "add the shard of subtree " + child.name() + " (or one above it)");
      }
    }
    for (const auto& r : records) {
      const std::string key = tiles::tileContentKey(r.id);
      if (const std::size_t i = from.at(key); i != kBuiltHere)
        stage->put(key, *shards[i]->get(key));
    }
    finish(stage, stagePath, out, records, build);
  } catch (...) {
    // The stage was made by this merge and is of no use to another; an
    // archive's SQLite files too (left when the disk filled up).
    stage.reset();
    std::error_code ec;
    if (fs::is_directory(stagePath, ec)) {
      fs::remove_all(stagePath, ec);
    } else {
      for (const char* suffix : {"", "-journal", "-wal", "-shm"})
        fs::remove(stagePath.string() + suffix, ec);
    }
    throw;
  }
  TileJobSummary summary = summarize(records, build);
  summary.built = builtHere;
  summary.reused = records.size() - builtHere;
  return summary;
}

StoreInfo describeTileStore(const fs::path& path) {
  auto st = store::openStoreForReading(path);
  StoreInfo info;
  if (auto b = st->get(kBuildKey)) info.build = *b;
  info.summary = summarize(storeRecords(*st), info.build);
  info.summary.terrain = describeTerrain(*st);
  // Complete when every scheme the build asked for has its index.
  const auto build = nlohmann::json::parse(info.build, nullptr, false);
  const auto scheme = parseTileScheme(
      build.is_object() ? build.value("/options/scheme"_json_pointer, std::string("3d-tiles"))
                        : std::string("3d-tiles"));
  const bool wants3d = !scheme || *scheme != TileScheme::QuantizedMesh;
  const bool wantsTerrain = scheme && *scheme != TileScheme::Tiles3D;
  info.missing.clear();
  if (wants3d && !st->contains("tileset.json")) info.missing = "tileset.json";
  if (wantsTerrain && !st->contains(kTerrainLayerKey))
    info.missing += std::string(info.missing.empty() ? "" : " and ") + kTerrainLayerKey;
  info.complete = info.missing.empty();
  return info;
}

}  // namespace tinsmith::ingest
