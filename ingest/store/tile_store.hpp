// Tile stores: where a tileset's files live. Keys are relative paths with '/'
// ("tileset.json", "tiles/3/2/5.glb", "tinsmith/terrain.tin"); a key is
// checked before use (no "..", no leading '/', no '\\', no empty segment, no
// NUL) and is never joined into a path without that check.
//
// Two kinds, chosen by the path (storeKindFor):
//   * Archive: one SQLite file (".3dtiles"), the one table 3d-tiles-tools reads,
//     media(key TEXT PRIMARY KEY, content BLOB). Each put is its own
//     transaction: a reader sees a tile whole or not at all.
//   * Directory: a folder of files; each put writes a temporary file beside
//     the target and renames it over (atomic on POSIX).
// Readers may run while a writer writes (SQLite WAL for a staging archive;
// readers open read-only).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace tinsmith::store {

enum class StoreKind { Archive, Directory };

/// Archive for a path ending in ".3dtiles" (any case), Directory otherwise.
StoreKind storeKindFor(const std::filesystem::path& path);

/// Whether a key is acceptable (see the file comment).
bool isValidKey(std::string_view key);

/// Every member may be called from several threads at once: an archive
/// opened for reading hands each call one of a few SQLite connections (get()
/// calls run side by side), an archive opened for writing serialises calls on
/// its one connection, and a directory store keeps no state but its root.
class TileStore {
 public:
  virtual ~TileStore() = default;
  [[nodiscard]] virtual StoreKind kind() const = 0;
  [[nodiscard]] virtual const std::filesystem::path& path() const = 0;
  /// The bytes of `key`, or nullopt when absent. Throws inputError for an
  /// invalid key, ioError when the store cannot be read.
  [[nodiscard]] virtual std::optional<std::string> get(std::string_view key) const = 0;
  [[nodiscard]] virtual bool contains(std::string_view key) const = 0;
  /// Every key, sorted bytewise.
  [[nodiscard]] virtual std::vector<std::string> keys() const = 0;
  /// Writes `bytes` under `key`, replacing what was there, atomically. Throws
  /// ioError naming the store and key (nothing half-written is left), or
  /// usageError on a store opened for reading.
  virtual void put(std::string_view key, std::string_view bytes) = 0;
};

/// Opens an existing store read-only. Throws inputError naming the path when
/// it is missing or not a store (a file that is not SQLite, an archive
/// without the media table).
std::unique_ptr<TileStore> openStoreForReading(const std::filesystem::path& path);

/// Opens a store for writing, creating it (and its parent folder) when absent.
/// `keepExisting` false empties an existing store first. Throws ioError
/// naming the path when it cannot be created or written.
std::unique_ptr<TileStore> openStoreForWriting(const std::filesystem::path& path,
                                               bool keepExisting);

/// Writes `keys` of `source`, in that order, as a new store at `target` (of
/// the kind its path names), atomically: the target appears complete or not
/// at all (an archive is written beside it and renamed; a directory is
/// written as a sibling folder and renamed over). An archive written from the
/// same keys and bytes in the same order has the same bytes, so one run, a
/// resumed run and merged shards give identical files. Throws inputError for
/// a key missing from `source`, ioError when the target cannot be written.
void writeStore(const TileStore& source, std::span<const std::string> keys,
                const std::filesystem::path& target);

}  // namespace tinsmith::store
