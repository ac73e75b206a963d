// Output files that appear all at once or not at all. Bytes go to a temp
// file in the target's directory (".NAME.HOST-PID.XXXXXX.part", a name made
// unique by mkstemps, so two writers of one target never share it);
// commit() fsyncs it and renames it over the target. If commit() is never
// reached (an exception, a failed write), the destructor removes the temp
// file, so a failed run leaves neither a partial file nor a stale temp
// behind. A killed run (SIGKILL, a lost node) runs no destructor: the next
// writer of the same target removes the temps of writers on its host whose
// process is gone (a temp from another host, or an older one without a
// host and process, is left: its writer may still be running).
//
//   AtomicFile  writes the bytes itself (.tin, OBJ, PLY, JSON reports);
//   AtomicPath  hands out the temp path to a library that writes by name
//               (GDAL, OpenEXR), then commits it the same way.
#pragma once

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace tinsmith::ingest {

class AtomicPath {
 public:
  /// Creates the (empty) temp file next to `target`. Throws ioError naming
  /// `target` when it names a directory, or its directory does not exist or
  /// is not writable.
  explicit AtomicPath(std::filesystem::path target);
  AtomicPath(const AtomicPath&) = delete;
  AtomicPath& operator=(const AtomicPath&) = delete;
  ~AtomicPath();

  /// Where to write: replace the file's contents, never rename or remove it.
  [[nodiscard]] const std::filesystem::path& temp() const { return temp_; }
  [[nodiscard]] const std::filesystem::path& target() const { return target_; }
  /// Fsyncs the temp file and renames it onto the target; the writer must
  /// have closed it. Throws ioError (and removes the temp file) on failure.
  void commit();
  /// Removes the temp file now (what the destructor does if not committed).
  void discard() noexcept;

 private:
  friend class AtomicFile;
  /// The temp file's descriptor, open for writing (AtomicFile takes it);
  /// -1 once taken or closed.
  int takeDescriptor();

  std::filesystem::path target_;
  std::filesystem::path temp_;
  int fd_ = -1;
  bool committed_ = false;
};

class AtomicFile {
 public:
  /// Opens the temp file next to `target`. Throws ioError naming `target` when
  /// its directory does not exist or is not writable.
  explicit AtomicFile(std::filesystem::path target);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  /// Appends bytes; throws ioError (disk full, i/o error) naming the target.
  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  /// Overwrites bytes already written at `offset` (for headers patched at the end).
  void writeAt(std::size_t offset, const void* data, std::size_t size);
  /// Flushes, fsyncs, closes and renames onto the target. Throws ioError.
  void commit();

  [[nodiscard]] const std::filesystem::path& target() const { return path_.target(); }

 private:
  [[noreturn]] void fail(const std::string& what);
  AtomicPath path_;
  std::FILE* file_ = nullptr;
};

}  // namespace tinsmith::ingest
