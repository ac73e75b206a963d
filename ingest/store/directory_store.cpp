// The directory store: one file per key under a root folder.
//
// Threads: every member may be called from several threads at once; the
// store keeps no state beyond its root, and each put writes its own uniquely
// named temporary file ("<file>.tmp-<pid>-<counter>.<host>") and renames it over the
// target, so readers see the old bytes or the new ones, never a mix. Puts are
// not fsynced one by one (a tileset has many thousands of files): they are
// atomic against readers and failures, not against a power cut.
#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "core/base/error.hpp"
#include "ingest/store/store_detail.hpp"

namespace tinsmith::store::detail {

namespace {

namespace fs = std::filesystem;

std::string errnoText() {
  return std::strerror(errno);
}

// Closes a file descriptor on every path out.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] int get() const { return fd_; }
  /// Closes now and reports whether close succeeded.
  bool close() {
    const int rc = ::close(fd_);
    fd_ = -1;
    return rc == 0;
  }

 private:
  int fd_;
};

class DirectoryStore final : public TileStore {
 public:
  DirectoryStore(fs::path root, Access access) : root_(std::move(root)), access_(access) {}

  [[nodiscard]] StoreKind kind() const override { return StoreKind::Directory; }
  [[nodiscard]] const fs::path& path() const override { return root_; }

  [[nodiscard]] std::optional<std::string> get(std::string_view key) const override {
    const fs::path file = fileFor(key);
    Fd fd(::open(file.c_str(), O_RDONLY | O_CLOEXEC));
    if (fd.get() < 0) {
      if (errno == ENOENT || errno == ENOTDIR) return std::nullopt;
      throw readFailure(key, errnoText());
    }
    struct stat info {};
    if (::fstat(fd.get(), &info) != 0) throw readFailure(key, errnoText());
    if (!S_ISREG(info.st_mode)) return std::nullopt;
    std::string bytes(static_cast<std::size_t>(info.st_size), '\0');
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::read(fd.get(), bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw readFailure(key, errnoText());
      if (n == 0) break;  // shrunk since fstat: keep what is there
      done += static_cast<std::size_t>(n);
    }
    bytes.resize(done);
    return bytes;
  }

  [[nodiscard]] bool contains(std::string_view key) const override {
    const fs::path file = fileFor(key);
    std::error_code ec;
    return fs::is_regular_file(file, ec);
  }

  [[nodiscard]] std::vector<std::string> keys() const override {
    std::vector<std::string> keys;
    std::error_code ec;
    fs::recursive_directory_iterator it(root_, ec);
    for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
      const std::string name = it->path().filename().string();
      // Files mid-put and folders mid-writeStore are not keys yet.
      std::error_code entry;
      if (isTempName(name)) {
        if (it->is_directory(entry)) it.disable_recursion_pending();
        continue;
      }
      if (!it->is_regular_file(entry)) continue;
      std::string key = it->path().lexically_relative(root_).generic_string();
      // A file no key can name (a backslash in its name) cannot be read back.
      if (isValidKey(key)) keys.push_back(std::move(key));
    }
    if (ec)
      throw ioError("cannot list the folder's files: " + ec.message(), fileLocation(root_),
                    "check permissions");
    std::sort(keys.begin(), keys.end());
    return keys;
  }

  void put(std::string_view key, std::string_view bytes) override {
    writeAtomically(key, [&](int fd) { writeAll(fd, bytes, key); });
  }

  [[nodiscard]] std::optional<std::uint64_t> size(std::string_view key) const override {
    const fs::path file = fileFor(key);
    struct stat info {};
    if (::stat(file.c_str(), &info) != 0) {
      if (errno == ENOENT || errno == ENOTDIR) return std::nullopt;
      throw readFailure(key, errnoText());
    }
    if (!S_ISREG(info.st_mode)) return std::nullopt;
    return static_cast<std::uint64_t>(info.st_size);
  }

  void read(std::string_view key, std::uint64_t offset, std::span<char> out) const override {
    const fs::path file = fileFor(key);
    Fd fd(::open(file.c_str(), O_RDONLY | O_CLOEXEC));
    if (fd.get() < 0) throw readFailure(key, errnoText());
    std::size_t done = 0;
    while (done < out.size()) {
      const ssize_t n = ::pread(fd.get(), out.data() + done, out.size() - done,
                                static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw readFailure(key, errnoText());
      if (n == 0)
        throw readFailure(key, "it ends at byte " + std::to_string(offset + done) + ", before " +
                                   std::to_string(offset + out.size()));
      done += static_cast<std::size_t>(n);
    }
  }

  void putInPieces(std::string_view key, std::uint64_t size, const PieceFiller& fill) override {
    writeAtomically(key, [&](int fd) {
      copyPieces(size, fill, [&](std::uint64_t, std::span<const char> piece) {
        writeAll(fd, {piece.data(), piece.size()}, key);
      });
    });
  }

 private:
  // The one place a key becomes a path, after the check.
  [[nodiscard]] fs::path fileFor(std::string_view key) const {
    requireValidKey(key, root_);
    return root_ / fs::path(std::string(key));
  }

  // A put: write(fd) fills a temporary file beside the key's, renamed over
  // it once closed; removed instead when anything throws.
  template <class Write>
  void writeAtomically(std::string_view key, Write&& write) {
    if (access_ == Access::Read)
      throw usageError("put into '" + root_.string() + "', which was opened for reading",
                       "open the store with openStoreForWriting");
    const fs::path file = fileFor(key);
    if (isTempName(file.filename().string()))
      throw inputError("the tile key '" + std::string(key) + "' ends like a temporary file's name",
                       fileLocation(root_),
                       "rename the tile; names ending in .tmp-N-N or .tmp-N-N.HOST are reserved");
    createFolderFor(file.parent_path(), root_);
    const fs::path temp = tempSibling(file);
    Fd fd(::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666));
    if (fd.get() < 0) throw writeFailure(key, "cannot create a file: " + errnoText());
    try {
      write(fd.get());
    } catch (...) {
      fd.close();
      discard(temp);
      throw;
    }
    if (!fd.close()) {
      const std::string reason = errnoText();
      discard(temp);
      throw writeFailure(key, "closing failed: " + reason);
    }
    if (::rename(temp.c_str(), file.c_str()) != 0) {
      const std::string reason = errnoText();
      discard(temp);
      throw writeFailure(key, "cannot move the file into place: " + reason);
    }
  }

  void writeAll(int fd, std::string_view bytes, std::string_view key) const {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw writeFailure(key, "writing failed: " + errnoText());
      done += static_cast<std::size_t>(n);
    }
  }

  static void discard(const fs::path& temp) {
    std::error_code ec;
    fs::remove(temp, ec);
  }

  [[nodiscard]] Error readFailure(std::string_view key, const std::string& reason) const {
    return ioError("cannot read the key '" + std::string(key) + "': " + reason, fileLocation(root_),
                   "check permissions");
  }
  [[nodiscard]] Error writeFailure(std::string_view key, const std::string& reason) const {
    return ioError("cannot write the key '" + std::string(key) + "': " + reason,
                   fileLocation(root_), "check free disk space and permissions");
  }

  fs::path root_;
  Access access_;
};

// Removes a half-written folder unless released.
class TempFolder {
 public:
  explicit TempFolder(fs::path path) : path_(std::move(path)) {}
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  ~TempFolder() {
    if (path_.empty()) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  [[nodiscard]] const fs::path& path() const { return path_; }
  void release() { path_.clear(); }

 private:
  fs::path path_;
};

}  // namespace

FolderSurvey surveyFolder(const fs::path& folder) {
  FolderSurvey survey;
  std::error_code ec;
  fs::recursive_directory_iterator it(folder, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    std::error_code entry;
    const fs::file_status status = it->symlink_status(entry);
    if (fs::is_directory(status)) continue;
    ++survey.files;
    const std::string key = it->path().lexically_relative(folder).generic_string();
    if (key == kStoreMarkerKey) survey.marker = true;
    const bool ours = fs::is_regular_file(status) &&
                      (isTempName(it->path().filename().string()) ||
                       (isValidKey(key) && isStoreKey(key)));
    if (ours) continue;
    if (survey.foreign++ == 0) survey.firstForeign = key;
  }
  if (ec)
    throw ioError("cannot list the folder's files: " + ec.message(), fileLocation(folder),
                  "check permissions");
  return survey;
}

void removeStoreFolder(const fs::path& folder) {
  std::error_code ec;
  const fs::path marker = folder / fs::path(std::string(kStoreMarkerKey));
  const fs::path markerFolder = marker.parent_path();
  auto fail = [&](const std::error_code& e) {
    return ioError("cannot remove the old tile folder: " + e.message(), fileLocation(folder),
                   "check permissions");
  };
  // Everything but the marker's folder, then that folder but the marker.
  for (const fs::path& dir : {folder, markerFolder}) {
    fs::directory_iterator it(dir, ec);
    if (ec == std::errc::no_such_file_or_directory) continue;
    if (ec) throw fail(ec);
    std::vector<fs::path> doomed;
    for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
      if (it->path() != markerFolder && it->path() != marker) doomed.push_back(it->path());
    }
    if (ec) throw fail(ec);
    for (const fs::path& p : doomed) {
      fs::remove_all(p, ec);
      if (ec) throw fail(ec);
    }
  }
  fs::remove_all(folder, ec);
  if (ec) throw fail(ec);
}

void moveFolderStore(const fs::path& staged, const fs::path& target) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(target, ec))) {
    fs::rename(staged, target, ec);
    if (ec)
      throw ioError("cannot move the finished folder into place: " + ec.message(),
                    fileLocation(target), "check that the target's folder is writable");
    return;
  }
  // One atomic step where the filesystem has it: the new store takes the
  // name and the old one takes the staged name, to be removed.
  if (::renameat2(AT_FDCWD, staged.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) == 0) {
    try {
      removeStoreFolder(staged);
    } catch (const Error&) {
      // The new store is in place; the old one stays under the staged name,
      // which the next run empties.
    }
    return;
  }
  if (errno != EINVAL && errno != ENOSYS && errno != ENOTSUP)
    throw ioError("cannot move the finished folder into place: " + errnoText(),
                  fileLocation(target), "check that the target's folder is writable");
  // Elsewhere, two renames: the old folder moves aside first, and comes back
  // if the new one cannot take its place.
  const fs::path aside = tempSibling(target);
  fs::rename(target, aside, ec);
  if (ec)
    throw ioError("cannot move the old folder aside: " + ec.message(), fileLocation(target),
                  "check that the target's folder is writable");
  fs::rename(staged, target, ec);
  if (ec) {
    std::error_code back;
    fs::rename(aside, target, back);
    throw ioError("cannot move the finished folder into place: " + ec.message() +
                      (back ? "; the old folder is now '" + aside.string() + "'" : std::string()),
                  fileLocation(target), "check that the target's folder is writable");
  }
  try {
    removeStoreFolder(aside);
  } catch (const Error&) {
    // Left under a temporary name for removeStaleTemps.
  }
}

std::unique_ptr<TileStore> openDirectory(const fs::path& path, Access access) {
  std::error_code ec;
  const bool folder = fs::is_directory(path, ec);
  if (access == Access::Read) {
    if (!folder)
      throw inputError("is a file, not a tile folder", fileLocation(path),
                       "an archive's name ends in .3dtiles; a folder store is a folder");
    return std::make_unique<DirectoryStore>(path, access);
  }
  if (!folder && fs::exists(fs::symlink_status(path, ec)))
    throw ioError("the tile folder's path is taken by a file", fileLocation(path),
                  "remove it or choose another output path (an archive's name ends in .3dtiles)");
  if (folder && access == Access::Fresh) removeStoreFolder(path);
  createFolderFor(path, path);
  return std::make_unique<DirectoryStore>(path, access);
}

void writeDirectory(const TileStore& source, std::span<const std::string> keys,
                    const fs::path& target) {
  createFolderFor(target.parent_path(), target);
  std::error_code ec;
  const bool exists = fs::exists(fs::symlink_status(target, ec));
  if (exists && !fs::is_directory(fs::symlink_status(target, ec)))
    throw ioError("the target is a file, not a tile folder", fileLocation(target),
                  "remove it or choose another output path (an archive's name ends in .3dtiles)");

  TempFolder staged(tempSibling(target));
  {
    DirectoryStore out(staged.path(), Access::Fresh);
    createFolderFor(staged.path(), target);
    for (const std::string& key : keys) {
      if (out.contains(key))
        throw inputError("the key '" + key + "' is listed twice for the folder",
                         fileLocation(target), "list each key once");
      copyValue(source, key, out);
    }
  }
  moveFolderStore(staged.path(), target);
  staged.release();
}

}  // namespace tinsmith::store::detail
