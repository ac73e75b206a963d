// Checks of an output path made before a command starts long work, so a
// mistake in it fails at once instead of after the build.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/base/error.hpp"

namespace tinsmith::cli {

/// Throws ioError naming `option` unless the folder `path` goes in exists and
/// this process may write there.
inline void checkOutputDirectory(const std::filesystem::path& path, const char* option) {
  const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  const char* problem = nullptr;
  if (!std::filesystem::exists(dir, ec))
    problem = "does not exist";
  else if (!std::filesystem::is_directory(dir, ec))
    problem = "is not a directory";
  else if (::access(dir.c_str(), W_OK) != 0)
    problem = "is not writable";
  if (problem) {
    throw ioError(
        std::string("cannot write ") + option + " there: '" + dir.string() + "' " + problem,
        fileLocation(path), "create the directory, or choose another path you may write to");
  }
}

}  // namespace tinsmith::cli
