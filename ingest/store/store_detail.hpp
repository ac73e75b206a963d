// What the two store kinds share behind tile_store.hpp: how a store is opened,
// the key check that throws, and the names of temporary files and folders.
// Not part of the public API; only ingest/store/*.cpp include it.
#pragma once

#include <filesystem>
#include <memory>
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

/// "<target>.tmp-<pid>-<counter>": unique within the machine while this process
/// lives, in the target's folder so that a rename onto the target is atomic.
std::filesystem::path tempSibling(const std::filesystem::path& target);

/// Whether a file or folder name ends the way tempSibling's names end.
bool isTempName(std::string_view name);

/// Creates `folder` and its parents; throws ioError naming `target` when it
/// cannot (a parent that is a regular file, no permission).
void createFolderFor(const std::filesystem::path& folder, const std::filesystem::path& target);

/// The bytes of `key` in `source`, for writeStore. Throws inputError naming
/// the source when the key is invalid or missing.
std::string bytesForCopy(const TileStore& source, const std::string& key);

std::unique_ptr<TileStore> openArchive(const std::filesystem::path& path, Access access);
std::unique_ptr<TileStore> openDirectory(const std::filesystem::path& path, Access access);

void writeArchive(const TileStore& source, std::span<const std::string> keys,
                  const std::filesystem::path& target);
void writeDirectory(const TileStore& source, std::span<const std::string> keys,
                    const std::filesystem::path& target);

}  // namespace tinsmith::store::detail
