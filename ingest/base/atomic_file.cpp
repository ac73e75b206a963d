#include "ingest/base/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "core/base/error.hpp"

namespace tinsmith::ingest {

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  const std::filesystem::path dir =
      target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".");
  if (target_.filename().empty())
    throw ioError("the output path names a directory, not a file", fileLocation(target_),
                  "give a file name such as out/site.tin");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw ioError("the output directory '" + dir.string() + "' does not exist",
                  fileLocation(target_), "create it first or choose another output path");
  std::string pattern = (dir / ("." + target_.filename().string() + ".XXXXXX.part")).string();
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  const int fd = ::mkstemps(name.data(), 5);
  if (fd < 0)
    throw ioError(
        std::string("cannot create a file in '") + dir.string() + "': " + std::strerror(errno),
        fileLocation(target_), "check that the directory is writable");
  temp_ = name.data();
  // mkstemp creates 0600; give the file the usual permissions (umask applies).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd, 0666 & ~mask);
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    ::close(fd);
    std::filesystem::remove(temp_, ec);
    throw ioError(std::string("cannot open the output: ") + std::strerror(errno),
                  fileLocation(target_));
  }
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 16);
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !temp_.empty()) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

void AtomicFile::fail(const std::string& what) {
  const std::string reason = std::strerror(errno);
  if (file_) std::fclose(file_);
  file_ = nullptr;
  std::error_code ec;
  std::filesystem::remove(temp_, ec);
  throw ioError(what + ": " + reason, fileLocation(target_),
                "check free disk space and permissions");
}

void AtomicFile::write(const void* data, std::size_t size) {
  if (!file_) throw internalError("AtomicFile::write after close");
  if (size && std::fwrite(data, 1, size, file_) != size) fail("writing failed");
}

void AtomicFile::writeAt(std::size_t offset, const void* data, std::size_t size) {
  if (!file_) throw internalError("AtomicFile::writeAt after close");
  const long back = std::ftell(file_);
  if (back < 0 || std::fseek(file_, static_cast<long>(offset), SEEK_SET) != 0) fail("seeking failed");
  write(data, size);
  if (std::fseek(file_, back, SEEK_SET) != 0) fail("seeking failed");
}

void AtomicFile::commit() {
  if (!file_) throw internalError("AtomicFile::commit twice");
  if (std::fflush(file_) != 0) fail("writing failed");
  if (::fsync(::fileno(file_)) != 0) fail("syncing to disk failed");
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) fail("closing failed");
  std::error_code ec;
  std::filesystem::rename(temp_, target_, ec);
  if (ec) {
    std::filesystem::remove(temp_, ec);
    throw ioError("cannot move the finished file into place: " + ec.message(),
                  fileLocation(target_),
                  "check that the target is not a directory and is writable");
  }
  committed_ = true;
}

}  // namespace tinsmith::ingest
