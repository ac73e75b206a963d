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
//
// Ownership: a store never deletes what is not its own. Writing over an
// existing path (openStoreForWriting without keepExisting, writeStore,
// moveStore) first requires it to be replaceable (requireReplaceable): absent,
// an empty folder, or a tinsmith store — it holds kStoreMarkerKey and nothing
// but store keys. Anything else is refused, naming a file that would be lost.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
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

/// The key every tinsmith store holds, written first by the tile job: what
/// marks a folder or an archive as a tinsmith store.
inline constexpr std::string_view kStoreMarkerKey = "tinsmith/build.json";

/// Whether `key` is one a tinsmith store writes: "tileset.json", or a key
/// under "tiles/", "tilesets/", "terrain/" (Cesium terrain) or "tinsmith/".
bool isStoreKey(std::string_view key);

/// Throws ioError naming `path` unless a new store may take its place with
/// nothing lost: nothing is there, or an empty folder, or an archive or
/// folder store that holds kStoreMarkerKey and only store keys (a folder
/// store may also hold the temporary files of a put, and empty folders). The
/// message names a file that is not the store's and says how many there are.
void requireReplaceable(const std::filesystem::path& path);

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

  /// The size in bytes of `key`'s value, without reading it; nullopt when
  /// absent. Throws as get().
  [[nodiscard]] virtual std::optional<std::uint64_t> size(std::string_view key) const = 0;
  /// Reads out.size() bytes of `key`'s value from `offset`: a value is read
  /// a piece at a time without holding it whole. Throws ioError naming the
  /// store and key when it is absent or ends before offset + out.size().
  virtual void read(std::string_view key, std::uint64_t offset, std::span<char> out) const = 0;
  /// Hands fill(offset, piece) one piece of a value after another, in order,
  /// each to be filled with the bytes at `offset`.
  using PieceFiller = std::function<void(std::uint64_t offset, std::span<char> piece)>;
  /// put() of a value of `size` bytes written a piece at a time (at most
  /// kCopyPieceBytes held): atomic as put, and nothing is left of it when
  /// `fill` throws (which is rethrown).
  virtual void putInPieces(std::string_view key, std::uint64_t size, const PieceFiller& fill) = 0;
};

/// The largest piece copyValue, writeStore and putInPieces hold of a value.
inline constexpr std::size_t kCopyPieceBytes = std::size_t{8} << 20;

/// Copies `key`'s value from one store to another, a piece at a time when it
/// is larger than kCopyPieceBytes (a TIN's piece is up to 256 MiB). Throws
/// inputError naming `from` when the key is invalid or missing there, and
/// what from.read and to.put throw.
void copyValue(const TileStore& from, std::string_view key, TileStore& to);

/// Which file (or folder) a path names: its device and inode. A store
/// renamed over the path is another file; the same file is the same store
/// version.
struct FileIdentity {
  std::uint64_t device = 0;
  std::uint64_t inode = 0;
  friend bool operator==(const FileIdentity&, const FileIdentity&) = default;
};
/// The identity of what `path` names now; nullopt when nothing is there.
std::optional<FileIdentity> fileIdentity(const std::filesystem::path& path);

/// Opens an existing store read-only. Throws inputError naming the path when
/// it is missing or not a store (a file that is not SQLite, an archive
/// without the media table).
std::unique_ptr<TileStore> openStoreForReading(const std::filesystem::path& path);

/// Opens a store for writing, creating it (and its parent folder) when absent.
/// `keepExisting` false empties an existing store first, which must be
/// replaceable (requireReplaceable); `keepExisting` true requires an existing
/// non-empty one to hold kStoreMarkerKey. Throws ioError naming the path when it
/// is not a store or cannot be created or written.
std::unique_ptr<TileStore> openStoreForWriting(const std::filesystem::path& path,
                                               bool keepExisting);

/// Writes `keys` of `source`, in that order, as a new store at `target` (of
/// the kind its path names), atomically: the target appears complete or not
/// at all (an archive is written beside it and renamed; a directory is
/// written as a sibling folder and renamed over). An archive written from the
/// same keys and bytes in the same order has the same bytes, so one run, a
/// resumed run and merged shards give identical files. Throws inputError for
/// a key missing from `source`, ioError when the target is not replaceable
/// (requireReplaceable) or cannot be written.
void writeStore(const TileStore& source, std::span<const std::string> keys,
                const std::filesystem::path& target);

/// Moves the finished folder store `staged` to `target` (a folder store's
/// path, which must be replaceable), atomically: readers of `target` see the
/// old store or the new one, and a process killed at any point leaves one of
/// them whole under `target`. The old store is then removed, its marker key
/// last (a removal cut short leaves a store that is still replaceable).
/// Throws ioError naming the paths when the move fails; `staged` is then
/// left as it was.
void moveStore(const std::filesystem::path& staged, const std::filesystem::path& target);

/// Removes temporary siblings of `target` (tempSibling names) that processes
/// no longer running left behind: half-written archives and folders, and old
/// stores that were moved aside. Best effort; errors are ignored.
void removeStaleTemps(const std::filesystem::path& target);

}  // namespace tinsmith::store
