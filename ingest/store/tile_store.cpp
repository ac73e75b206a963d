// The store-kind-independent half of tile_store.hpp: the key rule, the kind a
// path names, temporary names, and the open/write entry points that pick the
// archive or directory implementation.
#include "ingest/store/tile_store.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>

#include "core/base/error.hpp"
#include "ingest/store/store_detail.hpp"

namespace tinsmith::store {

namespace {

constexpr std::string_view kArchiveSuffix = ".3dtiles";
constexpr std::string_view kTempMarker = ".tmp-";

bool allDigits(std::string_view text) {
  return !text.empty() &&
         std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// A trailing '/' ("out/") names the same folder as "out"; temporary siblings
// and kinds are computed from the last real component.
std::filesystem::path withoutTrailingSlash(std::filesystem::path path) {
  while (!path.has_filename() && path.has_relative_path()) path = path.parent_path();
  return path;
}

}  // namespace

StoreKind storeKindFor(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  if (name.size() < kArchiveSuffix.size()) return StoreKind::Directory;
  const std::string_view tail = std::string_view(name).substr(name.size() - kArchiveSuffix.size());
  const bool archive =
      std::equal(tail.begin(), tail.end(), kArchiveSuffix.begin(),
                 [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; });
  return archive ? StoreKind::Archive : StoreKind::Directory;
}

bool isValidKey(std::string_view key) {
  if (key.empty() || key.front() == '/') return false;
  if (key.find('\\') != std::string_view::npos || key.find('\0') != std::string_view::npos)
    return false;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = std::min(key.find('/', begin), key.size());
    const std::string_view segment = key.substr(begin, end - begin);
    if (segment.empty() || segment == "." || segment == "..") return false;
    if (end == key.size()) return true;
    begin = end + 1;
  }
}

namespace detail {

void requireValidKey(std::string_view key, const std::filesystem::path& store) {
  if (isValidKey(key)) return;
  std::string shown;
  for (const char c : key) shown += c == '\0' ? std::string("\\0") : std::string(1, c);
  throw inputError("invalid tile key '" + shown + "'", fileLocation(store),
                   "a key is a relative path with '/' between non-empty segments, without '.', "
                   "'..', '\\' or NUL");
}

std::filesystem::path tempSibling(const std::filesystem::path& target) {
  static std::atomic<unsigned long long> counter{0};
  const std::filesystem::path base = withoutTrailingSlash(target);
  std::string name = base.filename().string();
  name += kTempMarker;
  name += std::to_string(::getpid());
  name += '-';
  name += std::to_string(counter.fetch_add(1, std::memory_order_relaxed));
  return base.parent_path() / name;
}

bool isTempName(std::string_view name) {
  const std::size_t marker = name.rfind(kTempMarker);
  if (marker == std::string_view::npos || marker == 0) return false;
  const std::string_view numbers = name.substr(marker + kTempMarker.size());
  const std::size_t dash = numbers.find('-');
  if (dash == std::string_view::npos) return false;
  return allDigits(numbers.substr(0, dash)) && allDigits(numbers.substr(dash + 1));
}

void createFolderFor(const std::filesystem::path& folder, const std::filesystem::path& target) {
  if (folder.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec || !std::filesystem::is_directory(folder))
    throw ioError("cannot create the folder '" + folder.string() + "'" +
                      (ec ? ": " + ec.message() : std::string()),
                  fileLocation(target),
                  "check that no part of the path is a file and that it is writable");
}

std::string bytesForCopy(const TileStore& source, const std::string& key) {
  requireValidKey(key, source.path());
  std::optional<std::string> bytes = source.get(key);
  if (!bytes)
    throw inputError("the key '" + key + "' to be copied is not in the store",
                     fileLocation(source.path()), "list only keys the store holds");
  return std::move(*bytes);
}

}  // namespace detail

std::unique_ptr<TileStore> openStoreForReading(const std::filesystem::path& path) {
  const std::filesystem::path clean = withoutTrailingSlash(path);
  std::error_code ec;
  if (!std::filesystem::exists(clean, ec))
    throw inputError("the tile store does not exist", fileLocation(clean),
                     "check the path; an archive is a .3dtiles file, a directory store a folder");
  if (storeKindFor(clean) == StoreKind::Archive)
    return detail::openArchive(clean, detail::Access::Read);
  return detail::openDirectory(clean, detail::Access::Read);
}

std::unique_ptr<TileStore> openStoreForWriting(const std::filesystem::path& path,
                                               bool keepExisting) {
  const std::filesystem::path clean = withoutTrailingSlash(path);
  if (clean.empty()) throw ioError("the tile store path is empty", {}, "give an output path");
  const detail::Access access = keepExisting ? detail::Access::Resume : detail::Access::Fresh;
  if (storeKindFor(clean) == StoreKind::Archive) return detail::openArchive(clean, access);
  return detail::openDirectory(clean, access);
}

void writeStore(const TileStore& source, std::span<const std::string> keys,
                const std::filesystem::path& target) {
  const std::filesystem::path clean = withoutTrailingSlash(target);
  if (clean.empty()) throw ioError("the tile store path is empty", {}, "give an output path");
  if (storeKindFor(clean) == StoreKind::Archive)
    detail::writeArchive(source, keys, clean);
  else
    detail::writeDirectory(source, keys, clean);
}

}  // namespace tinsmith::store
