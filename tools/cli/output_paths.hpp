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
  if (!std::filesystem::is_directory(dir, ec))
    throw ioError(std::string("the directory of ") + option + " '" + dir.string() +
                      "' does not exist",
                  {path.string(), {}, {}, {}}, "create it first or choose another path");
  if (::access(dir.c_str(), W_OK) != 0)
    throw ioError(std::string("the directory of ") + option + " '" + dir.string() +
                      "' is not writable",
                  {path.string(), {}, {}, {}}, "choose a folder you may write to");
}

}  // namespace tinsmith::cli
