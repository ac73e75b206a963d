// Runs a shell command and captures its exit code, stdout and stderr — for
// tests that drive the `tinsmith` binary the way a user does.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

namespace tinsmith::test {

struct CommandResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};

/// A fresh directory for one test's files, under TINSMITH_TEST_TMP (or the
/// system temp directory), emptied if it exists.
inline std::filesystem::path scratchDir(const std::string& name) {
  const char* root = std::getenv("TINSMITH_TEST_TMP");
  std::filesystem::path dir =
      std::filesystem::path(root ? root : std::filesystem::temp_directory_path().string()) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// How many entries a directory holds (a test that a failed write left nothing behind).
inline std::size_t filesIn(const std::filesystem::path& dir) {
  return static_cast<std::size_t>(std::distance(std::filesystem::directory_iterator(dir),
                                                std::filesystem::directory_iterator()));
}

/// Runs `command` with /bin/sh; stdin is /dev/null.
inline CommandResult runCommand(const std::string& command) {
  static int counter = 0;
  const auto errPath = std::filesystem::temp_directory_path() /
                       ("tinsmith-test-stderr-" + std::to_string(::getpid()) + "-" +
                        std::to_string(counter++));
  const std::string full = command + " </dev/null 2>" + errPath.string();
  CommandResult result;
  FILE* pipe = ::popen(full.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.out.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.err = readFile(errPath);
  std::filesystem::remove(errPath);
  return result;
}

/// The tinsmith binary under test followed by `arguments`.
inline CommandResult runTinsmith(const std::string& arguments) {
  return runCommand(std::string(TINSMITH_BINARY) + " " + arguments);
}

}  // namespace tinsmith::test
