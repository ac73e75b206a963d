// An output file that appears all at once or not at all: bytes go to a temp
// file in the target's directory (".NAME.XXXXXX.part"); commit() flushes,
// fsyncs and renames it over the target. If commit() is never reached (an
// exception, a failed write), the destructor removes the temp file, so a failed
// run leaves neither a partial file nor a stale temp behind.
#pragma once

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace tinsmith::ingest {

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

  [[nodiscard]] const std::filesystem::path& target() const { return target_; }

 private:
  void fail(const std::string& what);
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

}  // namespace tinsmith::ingest
