// The store-kind-independent half of tile_store.hpp: the key rule, the kind a
// path names, temporary names, and the open/write entry points that pick the
// archive or directory implementation.
#include "ingest/store/tile_store.hpp"

#include <signal.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

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

bool isStoreKey(std::string_view key) {
  if (key == "tileset.json") return true;
  for (const std::string_view folder : {"tiles/", "tilesets/", "terrain/", "tinsmith/"})
    if (key.size() > folder.size() && key.starts_with(folder)) return true;
  return false;
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
  name += '.';
  name += thisHostTag();
  return base.parent_path() / name;
}

const std::string& thisHostTag() {
  static const std::string tag = [] {
    std::string identity(256, '\0');
    if (::gethostname(identity.data(), identity.size()) != 0) identity.clear();
    identity.resize(identity.find('\0') == std::string::npos ? identity.size()
                                                             : identity.find('\0'));
    std::error_code ec;
    identity += '\n' + std::filesystem::read_symlink("/proc/self/ns/pid", ec).string();
    std::uint32_t hash = 2166136261U;  // FNV-1a
    for (const unsigned char c : identity) hash = (hash ^ c) * 16777619U;
    char hex[9];
    std::snprintf(hex, sizeof hex, "%08x", hash);
    return std::string(hex);
  }();
  return tag;
}

std::optional<TempWriter> tempWriter(std::string_view name) {
  const std::size_t marker = name.rfind(kTempMarker);
  if (marker == std::string_view::npos || marker == 0) return std::nullopt;
  std::string_view rest = name.substr(marker + kTempMarker.size());
  TempWriter writer;
  // "<pid>-<counter>.<host>", or an older tinsmith's "<pid>-<counter>".
  if (rest.size() > 9 && rest[rest.size() - 9] == '.') {
    const std::string_view host = rest.substr(rest.size() - 8);
    if (!std::all_of(host.begin(), host.end(), [](char c) {
          return std::isdigit(static_cast<unsigned char>(c)) || (c >= 'a' && c <= 'f');
        }))
      return std::nullopt;
    writer.host = host;
    rest.remove_suffix(9);
  }
  const std::size_t dash = rest.find('-');
  if (dash == std::string_view::npos || !allDigits(rest.substr(0, dash)) ||
      !allDigits(rest.substr(dash + 1)) || dash > 18)
    return std::nullopt;
  writer.pid = std::stol(std::string(rest.substr(0, dash)));
  return writer;
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

std::uint64_t sizeForCopy(const TileStore& source, std::string_view key) {
  requireValidKey(key, source.path());
  const std::optional<std::uint64_t> size = source.size(key);
  if (!size)
    throw inputError("the key '" + std::string(key) + "' to be copied is not in the store",
                     fileLocation(source.path()), "list only keys the store holds");
  return *size;
}

void copyPieces(std::uint64_t size, const TileStore::PieceFiller& fill,
                const std::function<void(std::uint64_t offset, std::span<const char> piece)>& write) {
  std::vector<char> piece(static_cast<std::size_t>(std::min<std::uint64_t>(size, kCopyPieceBytes)));
  for (std::uint64_t offset = 0; offset < size;) {
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(piece.size(), size - offset));
    fill(offset, {piece.data(), n});
    write(offset, {piece.data(), n});
    offset += n;
  }
}

}  // namespace detail

void copyValue(const TileStore& from, std::string_view key, TileStore& to) {
  const std::uint64_t size = detail::sizeForCopy(from, key);
  if (size <= kCopyPieceBytes) {
    to.put(key, detail::bytesForCopy(from, std::string(key)));
    return;
  }
  to.putInPieces(key, size, [&](std::uint64_t offset, std::span<char> piece) {
    from.read(key, offset, piece);
  });
}

namespace {

[[noreturn]] void refuseReplacing(const std::filesystem::path& path, const std::string& problem) {
  throw ioError(problem, fileLocation(path),
                "choose another output path, or move what is there away: tinsmith replaces "
                "only a tile store it wrote (one holding " +
                    std::string(kStoreMarkerKey) + ")");
}

// An archive a run was killed in before it made its table: an empty file or
// a SQLite database without tables holds nothing to lose.
bool holdsNoTable(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 && !ec) return true;
  sqlite3* db = nullptr;
  bool empty = false;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* count = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM sqlite_master", -1, &count, nullptr) ==
            SQLITE_OK &&
        sqlite3_step(count) == SQLITE_ROW)
      empty = sqlite3_column_int(count, 0) == 0;
    sqlite3_finalize(count);
  }
  sqlite3_close_v2(db);
  return empty;
}

// A run killed while writing an archive leaves SQLite's sidecars beside it
// (the staging archive's WAL, or a hot rollback journal). A read-only
// connection may not recover them ("attempt to write a readonly database");
// one that may write does on its first read, bringing the archive to its
// last committed state, as any writer of it would first.
void recoverInterruptedWrite(const std::filesystem::path& path) {
  bool sidecar = false;
  for (const char* suffix : {"-journal", "-wal"}) {
    std::error_code ec;
    sidecar = sidecar || std::filesystem::exists(path.string() + suffix, ec);
  }
  if (!sidecar) return;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK)
    sqlite3_exec(db, "SELECT count(*) FROM sqlite_master", nullptr, nullptr, nullptr);
  sqlite3_close_v2(db);
}

// Whether another connection holds `path` locked now (a run writing it, in
// SQLite's exclusive locking mode, or any process in a transaction on it).
bool lockedByAnother(const std::filesystem::path& path) {
  sqlite3* db = nullptr;
  int rc = sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  if (rc == SQLITE_OK)
    rc = sqlite3_exec(db, "SELECT count(*) FROM sqlite_master", nullptr, nullptr, nullptr);
  sqlite3_close_v2(db);
  return (rc & 0xff) == SQLITE_BUSY || (rc & 0xff) == SQLITE_LOCKED;
}

std::string foreignText(std::size_t count, const std::string& first) {
  return "it holds '" + first + "'" +
         (count > 1 ? " and " + std::to_string(count - 1) + " other file" + (count > 2 ? "s" : "") +
                          " that are not a tile store's"
                    : std::string(", which is not a tile store's"));
}

}  // namespace

void requireReplaceable(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  const fs::path clean = withoutTrailingSlash(path);
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(clean, ec);
  if (!fs::exists(status)) return;
  if (fs::is_symlink(status))
    refuseReplacing(clean, "is a symbolic link, not a tile store (give the path it points to)");
  if (fs::is_directory(status)) {
    if (storeKindFor(clean) == StoreKind::Archive)
      refuseReplacing(clean, "is a folder, not a .3dtiles archive");
    const detail::FolderSurvey survey = detail::surveyFolder(clean);
    if (survey.foreign > 0)
      refuseReplacing(clean, "is a folder that is not a tinsmith tile store: " +
                                 foreignText(survey.foreign, survey.firstForeign));
    if (!survey.marker && survey.files > 0)
      refuseReplacing(clean, "is a folder that is not a tinsmith tile store (it has no " +
                                 std::string(kStoreMarkerKey) + ")");
    return;
  }
  if (!fs::is_regular_file(status) || storeKindFor(clean) != StoreKind::Archive)
    refuseReplacing(clean, "is a file, not a tile folder");
  recoverInterruptedWrite(clean);
  if (holdsNoTable(clean)) return;
  std::vector<std::string> keys;
  try {
    keys = detail::openArchive(clean, detail::Access::Read)->keys();
  } catch (const Error& e) {
    // Most likely a run that is writing it: not to be moved away.
    if (lockedByAnother(clean))
      throw ioError("is locked by another process (" + e.problem() + ")", fileLocation(clean),
                    "another run is probably writing it (tinsmith tile, merge or build to the "
                    "same output): wait for it to end, or give another output path; moving or "
                    "removing the archive while it runs loses that run's tiles");
    refuseReplacing(clean, "is not a tinsmith tile archive (" + e.problem() + ")");
  }
  std::size_t foreign = 0;
  std::string first;
  bool marker = false;
  for (const std::string& key : keys) {
    marker = marker || key == kStoreMarkerKey;
    if (!isStoreKey(key) && foreign++ == 0) first = key;
  }
  if (foreign > 0)
    refuseReplacing(
        clean, "is an archive that is not a tinsmith tile store: " + foreignText(foreign, first));
  if (!marker && !keys.empty())
    refuseReplacing(clean, "is an archive that is not a tinsmith tile store (it has no " +
                               std::string(kStoreMarkerKey) + ")");
}

std::optional<FileIdentity> fileIdentity(const std::filesystem::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  return FileIdentity{static_cast<std::uint64_t>(st.st_dev), static_cast<std::uint64_t>(st.st_ino)};
}

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
  if (!keepExisting) requireReplaceable(clean);
  const detail::Access access = keepExisting ? detail::Access::Resume : detail::Access::Fresh;
  std::unique_ptr<TileStore> store = storeKindFor(clean) == StoreKind::Archive
                                         ? detail::openArchive(clean, access)
                                         : detail::openDirectory(clean, access);
  // Kept content must be a store's: tiles are never added to other files.
  if (keepExisting && !store->contains(kStoreMarkerKey) && !store->keys().empty())
    refuseReplacing(
        clean, "is not a tinsmith tile store (it has no " + std::string(kStoreMarkerKey) + ")");
  return store;
}

void writeStore(const TileStore& source, std::span<const std::string> keys,
                const std::filesystem::path& target) {
  const std::filesystem::path clean = withoutTrailingSlash(target);
  if (clean.empty()) throw ioError("the tile store path is empty", {}, "give an output path");
  requireReplaceable(clean);
  if (storeKindFor(clean) == StoreKind::Archive)
    detail::writeArchive(source, keys, clean);
  else
    detail::writeDirectory(source, keys, clean);
}

void moveStore(const std::filesystem::path& staged, const std::filesystem::path& target) {
  const std::filesystem::path clean = withoutTrailingSlash(target);
  if (storeKindFor(clean) != StoreKind::Directory)
    throw internalError("moveStore is for folder stores, not '" + clean.string() + "'");
  requireReplaceable(clean);
  detail::moveFolderStore(withoutTrailingSlash(staged), clean);
}

void removeStaleTemps(const std::filesystem::path& target) {
  namespace fs = std::filesystem;
  const fs::path clean = withoutTrailingSlash(target);
  const std::string prefix = clean.filename().string() + std::string(kTempMarker);
  const fs::path folder = clean.has_parent_path() ? clean.parent_path() : fs::path(".");
  std::error_code ec;
  const bool targetExists = fs::exists(clean, ec);
  std::vector<fs::path> stale;
  fs::directory_iterator it(folder, ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
    std::string name = it->path().filename().string();
    if (!name.starts_with(prefix)) continue;
    for (const std::string_view sidecar : {"-journal", "-wal", "-shm"})
      if (name.ends_with(sidecar)) name.resize(name.size() - sidecar.size());
    const auto writer = detail::tempWriter(name);
    if (!writer || name.rfind(kTempMarker) != prefix.size() - kTempMarker.size()) continue;
    // A process id tells of a process on this machine only: another
    // machine's writer, on a shared filesystem, may still run.
    if (!writer->host.empty() && writer->host != detail::thisHostTag()) continue;
    const long pid = writer->pid;
    if (pid <= 0 || pid == ::getpid() || ::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH)
      continue;  // its writer may still run
    std::error_code entry;
    // A folder may be the only copy of an old store (moved aside by a run
    // killed before the new one took its name): kept unless the target is there.
    if (it->is_directory(entry) && !targetExists) continue;
    stale.push_back(it->path());
  }
  for (const fs::path& p : stale) fs::remove_all(p, ec);
}

}  // namespace tinsmith::store
