#include "ingest/tiles/tile_rebuild.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/base/error.hpp"
#include "core/tiles/pyramid_build.hpp"
#include "core/tiles/tiler.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"

namespace tinsmith::ingest {

struct TileRebuilder::State {
  TinData tin;
  std::unique_ptr<ProjGeoReference> geo;
  tiles::ContentOptions content;
  std::unique_ptr<tiles::Tiler> tiler;
  /// The record's: the tiles above it were fitted to its tiles' mosaic.
  int mosaicZoom = 0;
};

namespace {

/// The record's fields, each looked up (a store is a file from outside).
struct BuildRecord {
  nlohmann::json j;
  std::string store;

  const nlohmann::json& at(const char* pointer) const {
    const nlohmann::json::json_pointer p(pointer);
    if (!j.contains(p))
      throw inputError(store + ": tinsmith/build.json has no " + pointer, {},
                       "rebuild the store with this version's tinsmith tile");
    return j.at(p);
  }
  double number(const char* pointer) const {
    const auto& v = at(pointer);
    if (!v.is_number())
      throw inputError(store + ": tinsmith/build.json's " + pointer + " is not a number");
    return v.get<double>();
  }
  std::string string(const char* pointer) const {
    const auto& v = at(pointer);
    if (!v.is_string())
      throw inputError(store + ": tinsmith/build.json's " + pointer + " is not a string");
    return v.get<std::string>();
  }
};

}  // namespace

TileRebuilder::TileRebuilder(std::string_view build, std::string_view tin, const std::string& store)
    : state_(std::make_unique<State>()) {
  BuildRecord r{nlohmann::json::parse(build, nullptr, false), store};
  if (!r.j.is_object() || r.j.value("format", "") != kTileBuildFormat)
    throw inputError(store + ": tinsmith/build.json is not a " + std::string(kTileBuildFormat) +
                         " build record (" +
                         (r.j.is_object() ? r.j.value("format", "no format") : "not JSON") +
                         "): its tiles were made by another version of tinsmith, and tiles "
                         "built now would not fit them",
                     {}, "rebuild the store with this version's tinsmith tile");
  if (crc32(tin) != static_cast<std::uint32_t>(r.number("/tin/crc32")))
    throw inputError(store + ": the TIN is not the one its tiles were built from (CRC differs)", {},
                     "rebuild the store with tinsmith tile");
  state_->tin = decodeTin(tin, store + ":tinsmith/terrain.tin");

  TileJobOptions o;
  o.tiler.tolerance = r.number("/options/tolerance");
  o.tiler.maxTriangles = static_cast<std::size_t>(r.number("/options/maxTriangles"));
  o.tiler.maxZoom = static_cast<int>(r.number("/options/maxZoom"));
  o.tiler.lambdaFactor = r.number("/options/lambdaFactor");
  // The finest zoom the store was planned with: no planning fit again.
  o.tiler.plannedFinestZoom = static_cast<int>(r.number("/pyramid/finestZoom"));
  const auto compression = parseCompression(r.string("/options/compression"));
  const auto frame = parseContentFrame(r.string("/options/frame"));
  o.geoid = r.string("/options/geoid");
  if (!compression || !frame || !isKnownGeoid(o.geoid))
    throw inputError(store +
                     ": tinsmith/build.json names a compression, frame or geoid this "
                     "version does not know");
  o.compression = *compression;
  o.frame = *frame;
  checkTileJobOptions(o);
  state_->mosaicZoom = static_cast<int>(r.number("/pyramid/mosaicZoom"));

  // As runTileJob does it: the same georeference, content options and tiler.
  state_->geo = std::make_unique<ProjGeoReference>(state_->tin.crs, o.geoid);
  o.tiler.geo = state_->geo.get();  // as runTileJob plans chord sag
  state_->tiler = std::make_unique<tiles::Tiler>(state_->tin, o.tiler);
  const tiles::Tiler& tiler = *state_->tiler;
  auto& content = state_->content;
  content.compression = o.compression;
  content.frame = o.frame;
  content.geo = state_->geo.get();
  content.localOrigin = pyramidCentre(tiler.geometry(), *state_->geo);

  const bool samePyramid =
      tiler.geometry().origin().x == r.number("/pyramid/origin/0") &&
      tiler.geometry().origin().y == r.number("/pyramid/origin/1") &&
      tiler.geometry().size() == r.number("/pyramid/size") &&
      tiler.levelsPerTile() == static_cast<int>(r.number("/pyramid/levelsPerTile")) &&
      tiler.maxZoom() == static_cast<int>(r.number("/options/maxZoom"));
  if (!samePyramid)
    throw inputError(store +
                         ": the pyramid planned again from its TIN differs from the one its "
                         "tiles were built on, so missing tiles cannot be built to match",
                     {}, "rebuild the whole store with tinsmith tile");
}

TileRebuilder::~TileRebuilder() = default;

int TileRebuilder::maxZoom() const {
  return state_->tiler->maxZoom();
}

std::optional<tiles::TileContent> TileRebuilder::build(const tiles::TileId& id) const {
  const tiles::Tiler& tiler = *state_->tiler;
  if (id.z < state_->mosaicZoom)
    throw inputError("tile " + id.name() + " is missing from the store, and it lies above zoom " +
                         std::to_string(state_->mosaicZoom) +
                         ", whose tiles' mosaic it was fitted to: it cannot be built from the TIN "
                         "alone",
                     {}, "rebuild the store with tinsmith tile (it stores every such tile)");
  const tiles::TileSurface s = tiler.buildTile(id);
  if (s.empty()) return std::nullopt;
  return tiles::encodeTile(s, tiles::skirtDepth(tiler, s.id, s.error), state_->content);
}

}  // namespace tinsmith::ingest
