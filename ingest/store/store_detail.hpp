// What the two store kinds share behind tile_store.hpp: how a store is opened,
// the key check that throws, and the names of temporary files and folders.
// Not part of the public API; only ingest/store/*.cpp include it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "core/base/error.hpp"
#include "ingest/store/tile_store.hpp"

namespace tinsmith::store::detail {

enum class Access {
  Read,    ///< existing store, read-only; put() is a usage error
  Resume,  ///< read-write, created when absent, content kept
  Fresh,   ///< read-write, emptied (or created) first
};

/// Throws inputError naming the store and the key when !isValidKey(key).
void requireValidKey(std::string_view key, const std::filesystem::path& store);

/// "<target>.tmp-<pid>-<counter>.<host>": unique among the machines sharing
/// the folder while this process lives (<host>, thisHostTag, names the
/// machine and its process-id space), in the target's folder so that a
/// rename onto the target is atomic.
std::filesystem::path tempSibling(const std::filesystem::path& target);

/// Eight hex digits of the host name and the process-id namespace: a
/// process id means a process only on the machine whose tag it carries.
const std::string& thisHostTag();

/// What a temporary name says of its writer: its process id, and its host's
/// tag (empty for a name an older tinsmith gave, "<pid>-<counter>").
struct TempWriter {
  long pid = 0;
  std::string host;
};
/// The writer of a name that ends the way tempSibling's names end (or an
/// older tinsmith's), or nothing.
std::optional<TempWriter> tempWriter(std::string_view name);
inline bool isTempName(std::string_view name) {
  return tempWriter(name).has_value();
}

/// Creates `folder` and its parents; throws ioError naming `target` when it
/// cannot (a parent that is a regular file, no permission).
void createFolderFor(const std::filesystem::path& folder, const std::filesystem::path& target);

/// The bytes of `key` in `source`, for writeStore. Throws inputError naming
/// the source when the key is invalid or missing.
std::string bytesForCopy(const TileStore& source, const std::string& key);
/// The size of `key` in `source`, for a copy a piece at a time; throws as
/// bytesForCopy.
std::uint64_t sizeForCopy(const TileStore& source, std::string_view key);

/// putInPieces' loop: pieces of at most kCopyPieceBytes of a value of `size`
/// bytes, each filled by `fill` and then handed to write(offset, piece), in
/// order, through one buffer.
void copyPieces(std::uint64_t size, const TileStore::PieceFiller& fill,
                const std::function<void(std::uint64_t offset, std::span<const char> piece)>& write);

/// What a folder holds, for requireReplaceable: whether it has the marker
/// key, and the files that are not the store's (not a store key, not a
/// put's temporary file; symbolic links and special files count too).
struct FolderSurvey {
  bool marker = false;
  std::size_t files = 0;
  std::size_t foreign = 0;
  std::string firstForeign;  ///< relative path of one foreign file
};
FolderSurvey surveyFolder(const std::filesystem::path& folder);

/// Removes a folder store (one that requireReplaceable accepts) with its
/// marker key last, so a removal cut short leaves a replaceable store.
/// Throws ioError naming `folder` when it cannot.
void removeStoreFolder(const std::filesystem::path& folder);

/// moveStore without the replaceable check (writeDirectory's own staged folder).
void moveFolderStore(const std::filesystem::path& staged, const std::filesystem::path& target);

std::unique_ptr<TileStore> openArchive(const std::filesystem::path& path, Access access);
std::unique_ptr<TileStore> openDirectory(const std::filesystem::path& path, Access access);

void writeArchive(const TileStore& source, std::span<const std::string> keys,
                  const std::filesystem::path& target);
void writeDirectory(const TileStore& source, std::span<const std::string> keys,
                    const std::filesystem::path& target);

}  // namespace tinsmith::store::detail
