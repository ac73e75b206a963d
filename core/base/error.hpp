// The one error family of tinsmith. Library code throws tinsmith::Error (never
// exits); the CLI maps ErrorKind to exit codes (tools/cli/exit_codes.hpp) and
// the server maps it to HTTP statuses, each in one place.
//
// A message says what is wrong, where (file, layer, feature, line) and what to
// do:  "contours.gpkg, layer 'contours', feature 17: attribute 'elev' is not
// numeric ('n/a') — give every contour a numeric elevation or drop the feature".
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace tinsmith {

enum class ErrorKind {
  Usage,           ///< bad command-line arguments or options
  Input,           ///< bad or unreadable input data: file, layer, feature, line
  Geometry,        ///< input that cannot make a valid triangulation
  Io,              ///< an output could not be written
  NotImplemented,  ///< a feature that does not exist yet
  Internal,        ///< a broken invariant: a bug in tinsmith
};

std::string_view toString(ErrorKind kind);

/// Where in the input a problem was found. Every field is optional.
struct SourceLocation {
  std::string file{};
  std::string layer{};
  std::optional<std::int64_t> feature{};  ///< feature id (OGR FID) or record index
  std::optional<std::int64_t> line{};     ///< 1-based line in a text file

  [[nodiscard]] bool empty() const;
  /// "file, layer 'L', feature F, line N" — only the fields that are set.
  [[nodiscard]] std::string str() const;
};

/// The location of a whole file (or any named input): `file` set, nothing
/// else. A std::filesystem::path converts to its native string.
inline SourceLocation fileLocation(std::string file) {
  return SourceLocation{std::move(file)};
}

class Error : public std::runtime_error {
 public:
  /// `problem` says what is wrong; `hint`, if given, what the user can do.
  Error(ErrorKind kind, std::string problem, SourceLocation where = {}, std::string hint = {});

  [[nodiscard]] ErrorKind kind() const noexcept { return kind_; }
  [[nodiscard]] const std::string& problem() const noexcept { return problem_; }
  [[nodiscard]] const SourceLocation& where() const noexcept { return where_; }
  [[nodiscard]] const std::string& hint() const noexcept { return hint_; }

 private:
  ErrorKind kind_;
  std::string problem_;
  SourceLocation where_;
  std::string hint_;
};

// Shorthands for the common kinds; each returns the error for `throw`.
Error usageError(std::string problem, std::string hint = {});
Error inputError(std::string problem, SourceLocation where = {}, std::string hint = {});
Error geometryError(std::string problem, SourceLocation where = {}, std::string hint = {});
Error ioError(std::string problem, SourceLocation where = {}, std::string hint = {});
Error notImplemented(std::string what);
Error internalError(std::string problem);

}  // namespace tinsmith
