#include "ingest/base/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <vector>

#include "core/base/error.hpp"

namespace tinsmith::ingest {

namespace {

std::string hostName() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0 || host[0] == '\0') return "host";
  return host;
}

/// Removes the temps of `name` in `dir` whose writer ran on `host` and is
/// gone: ".NAME.HOST-PID.XXXXXX.part" with no process PID.
void removeDeadWritersTemps(const std::filesystem::path& dir, const std::string& name,
                            const std::string& host) {
  const std::string prefix = "." + name + "." + host + "-", suffix = ".part";
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string entry = it->path().filename().string();
    if (entry.size() <= prefix.size() + suffix.size() + 7 || entry.rfind(prefix, 0) != 0 ||
        entry.compare(entry.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    // PID.XXXXXX between the prefix and the suffix.
    const std::string middle =
        entry.substr(prefix.size(), entry.size() - prefix.size() - suffix.size());
    const std::size_t dot = middle.find('.');
    if (dot == std::string::npos || dot == 0 || middle.size() - dot != 7) continue;
    const std::string pidText = middle.substr(0, dot);
    if (pidText.find_first_not_of("0123456789") != std::string::npos || pidText.size() > 9)
      continue;
    const pid_t pid = static_cast<pid_t>(std::stol(pidText));
    if (pid <= 0 || ::kill(pid, 0) == 0 || errno != ESRCH) continue;  // alive, or not ours to ask
    std::error_code removed;
    std::filesystem::remove(it->path(), removed);
  }
}

}  // namespace

AtomicPath::AtomicPath(std::filesystem::path target) : target_(std::move(target)) {
  const std::filesystem::path dir =
      target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".");
  if (target_.filename().empty())
    throw ioError("the output path names a directory, not a file", fileLocation(target_),
                  "give a file name such as out/site.tin");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw ioError("the output directory '" + dir.string() + "' does not exist",
                  fileLocation(target_), "create it first or choose another output path");
  const std::string host = hostName();
  removeDeadWritersTemps(dir, target_.filename().string(), host);
  std::string pattern = (dir / ("." + target_.filename().string() + "." + host + "-" +
                                std::to_string(::getpid()) + ".XXXXXX.part"))
                            .string();
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  fd_ = ::mkostemps(name.data(), 5, O_CLOEXEC);  // not inherited by child processes
  if (fd_ < 0)
    throw ioError(
        std::string("cannot create a file in '") + dir.string() + "': " + std::strerror(errno),
        fileLocation(target_), "check that the directory is writable");
  temp_ = name.data();
  // mkstemp creates 0600; give the file the usual permissions (umask applies).
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::fchmod(fd_, 0666 & ~mask);
}

AtomicPath::~AtomicPath() {
  if (!committed_) discard();
}

int AtomicPath::takeDescriptor() {
  const int fd = fd_;
  fd_ = -1;
  return fd;
}

void AtomicPath::discard() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
    temp_.clear();  // the name may be someone else's next
  }
}

void AtomicPath::commit() {
  if (committed_) throw internalError("AtomicPath::commit twice");
  if (fd_ >= 0) ::close(fd_);
  // fsync applies to the file, not the descriptor: a fresh one flushes what
  // the writer (GDAL, OpenEXR, a FILE*) wrote through its own.
  fd_ = ::open(temp_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0 || ::fsync(fd_) != 0) {
    const std::string reason = std::strerror(errno);
    discard();
    throw ioError("syncing to disk failed: " + reason, fileLocation(target_),
                  "check free disk space and permissions");
  }
  ::close(fd_);
  fd_ = -1;
  std::error_code ec;
  std::filesystem::rename(temp_, target_, ec);
  if (ec) {
    discard();
    throw ioError("cannot move the finished file into place: " + ec.message(),
                  fileLocation(target_),
                  "check that the target is not a directory and is writable");
  }
  committed_ = true;
}

AtomicFile::AtomicFile(std::filesystem::path target) : path_(std::move(target)) {
  const int fd = path_.takeDescriptor();
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    const std::string reason = std::strerror(errno);
    ::close(fd);
    throw ioError("cannot open the output: " + reason, fileLocation(path_.target()));
  }
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 16);
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
}

void AtomicFile::fail(const std::string& what) {
  const std::string reason = std::strerror(errno);
  if (file_) std::fclose(file_);
  file_ = nullptr;
  path_.discard();
  throw ioError(what + ": " + reason, fileLocation(path_.target()),
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
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) fail("closing failed");
  path_.commit();
}

}  // namespace tinsmith::ingest
