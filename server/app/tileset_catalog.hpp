// The tilesets a server holds: each store opened read-only, described once
// (the /tilesets entry, from tinsmith/build.json and tileset.json), and its
// TIN loaded on the first elevation query. Ids come from file names and are
// looked up, never joined into a path.
//
// A store replaced on disk (a new archive renamed over the old one, as
// `tinsmith tile` writes it; or a directory store's tileset.json rewritten)
// is picked up by refresh(): the new store is opened beside the old one and
// swapped in whole. A request holds the Tileset it started with, whose open
// SQLite connections keep reading the old file, so no response mixes the two
// (no torn read); the old one is closed when its last request ends.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/base/point.hpp"
#include "core/encode/frames.hpp"
#include "core/surface/surface.hpp"
#include "core/tiles/pyramid.hpp"
#include "ingest/filters/reproject.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/tile_rebuild.hpp"

namespace tinsmith::server {

class Tileset {
 public:
  /// Opens the store at `path` read-only and describes it. Throws inputError
  /// naming the path when it is not a store or has no tileset.json.
  Tileset(std::string id, const std::filesystem::path& path);
  ~Tileset();

  [[nodiscard]] const std::string& id() const { return id_; }
  /// Unique per opened store in this process: a reloaded store gets a new
  /// one, so what was cached of the old one is never served for it.
  [[nodiscard]] std::uint64_t generation() const { return generation_; }
  [[nodiscard]] const store::TileStore& store() const { return *store_; }
  /// The /tilesets entry: id, name, crs, bounds (lon/lat degrees from the
  /// root's region; the pyramid's square in the project CRS), heights,
  /// zooms, tile count, tolerance, links.
  [[nodiscard]] const nlohmann::ordered_json& summary() const { return summary_; }
  /// The deepest zoom of the pyramid (the build's maxZoom).
  [[nodiscard]] int maxZoom() const { return maxZoom_; }
  [[nodiscard]] const std::string& crs() const { return crs_; }

  /// Whether the store carries its TIN (tinsmith/terrain.tin).
  [[nodiscard]] bool hasTin() const { return hasTin_; }
  /// Whether the store holds 3D Tiles (tileset.json) and Cesium terrain
  /// (terrain/layer.json); at least one.
  [[nodiscard]] bool hasTiles3D() const { return hasTiles3D_; }
  [[nodiscard]] bool hasTerrain() const { return hasTerrain_; }
  /// The TIN's surface, loaded from tinsmith/terrain.tin on first use
  /// (thread-safe). Throws inputError when the store carries no TIN, ioError
  /// when it cannot be decoded (the store is damaged: a server-side fault).
  [[nodiscard]] const Surface& surface() const;
  /// On demand (--on-demand): whether the tileset's files (tileset.json and
  /// its external tilesets, read on first use) name this tile's content.
  /// Thread-safe.
  [[nodiscard]] bool references(const tiles::TileId& id) const;
  /// The store's tile rebuilder, made on first use from its build record and
  /// TIN (seconds: it plans the pyramid); a failure is kept and thrown again
  /// as ioError. Thread-safe.
  [[nodiscard]] const ingest::TileRebuilder& rebuilder() const;
  /// Writes a tile built on demand into the store, atomically (an archive:
  /// one SQLite transaction; a directory: a file renamed into place). Returns
  /// false, having written nothing, when the store cannot be opened for
  /// writing (then `why` says why, once). Thread-safe.
  bool keep(const std::string& key, std::string_view bytes, std::string& why) const;
  /// Whether keep() has opened (or tried to open) the store for writing: the archive's file
  /// then changes under its own name (TilesetCatalog::refresh knows).
  [[nodiscard]] bool writesInPlace() const { return writesInPlace_.load(); }

  /// Longitude, latitude (WGS84 degrees) into the project CRS. Thread-safe.
  /// Throws inputError when PROJ cannot transform the point.
  [[nodiscard]] Point2 fromLonLat(double lon, double lat) const;
  /// Project x, y, z (the TIN's) into WGS84 lon, lat and height above the
  /// ellipsoid, as the tiles were placed: through the geoid the store was
  /// built with (build.json options.geoid), if any. Thread-safe. Throws
  /// inputError when the store names no CRS or PROJ cannot convert.
  void toGeodetic(std::span<const Point3> in, std::span<encode::Geodetic> out) const;

 private:
  std::string id_;
  std::uint64_t generation_;
  std::unique_ptr<store::TileStore> store_;
  nlohmann::ordered_json summary_;
  int maxZoom_ = 0;
  bool hasTin_ = false, hasTiles3D_ = false, hasTerrain_ = false;
  std::string crs_;
  mutable std::once_flag surfaceOnce_;
  mutable std::unique_ptr<Surface> surface_;
  mutable std::once_flag referencesOnce_;
  mutable std::set<std::string> referenced_;  // content keys the tileset files name
  mutable std::once_flag rebuilderOnce_;
  mutable std::unique_ptr<ingest::TileRebuilder> rebuilder_;
  mutable std::string rebuilderError_;
  mutable std::mutex writerMutex_;
  mutable std::unique_ptr<store::TileStore> writer_;
  mutable std::atomic<bool> writesInPlace_{false};
  std::optional<store::FileIdentity> opened_;  // the store's file when opened
  mutable std::mutex transformMutex_;  // OGR transformations are not thread-safe
  mutable std::unique_ptr<ingest::CrsTransform> fromLonLat_;
  std::string geoid_;
  mutable std::mutex geodeticMutex_;  // guards the creation of geodetic_ only
  mutable std::unique_ptr<ingest::ProjGeoReference> geodetic_;
};

class TilesetCatalog {
 public:
  /// Each path is a store (a .3dtiles file, or a directory with a
  /// tileset.json) or a folder of stores (every *.3dtiles file and store
  /// directory directly in it, but for a tile job's staging names:
  /// "*.partial.3dtiles", "*.partial", "*.tmp-N-N"). The id is the file name
  /// without ".3dtiles", every byte other than [A-Za-z0-9_.-] a '-' (so a
  /// name that is not UTF-8 is served too; the list's "name" shows such
  /// bytes as \xNN). Throws
  /// usageError for a path that is neither or two stores with one id, and
  /// what Tileset throws for a store that cannot be served.
  explicit TilesetCatalog(const std::vector<std::filesystem::path>& paths);
  ~TilesetCatalog();

  /// The tileset with this id, or null. Thread-safe.
  [[nodiscard]] std::shared_ptr<const Tileset> find(std::string_view id) const;
  /// Every tileset, in the order given. Thread-safe.
  [[nodiscard]] std::vector<std::shared_ptr<const Tileset>> tilesets() const;
  /// Counts swaps: changes whenever refresh() swapped a store in.
  [[nodiscard]] std::uint64_t version() const { return version_.load(); }

  /// Reopens every store whose file (an archive) or tileset.json (a
  /// directory) changed since it was opened (inode, size or mtime), and
  /// adds the stores that appeared in the folders served. A store that
  /// cannot be opened now keeps serving its old version (a new one is tried
  /// again next time); a new store whose id is taken is not served. Returns
  /// one line per store reloaded, added or refused, for the log. Thread-safe
  /// with the readers; one refresh at a time.
  std::vector<std::string> refresh();

 private:
  struct Entry;
  using Entries = std::vector<std::shared_ptr<Entry>>;
  /// Null when `path`'s id is taken in `existing`; throws what Tileset throws.
  static std::shared_ptr<Entry> makeEntry(const std::filesystem::path& path, const Entries& existing);

  std::vector<std::filesystem::path> folders_;
  std::set<std::string> refused_;  // new stores not served for their id (refresh only)
  std::atomic<std::shared_ptr<const Entries>> entries_;
  std::atomic<std::uint64_t> version_{0};
};

}  // namespace tinsmith::server
