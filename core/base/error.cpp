#include "core/base/error.hpp"

#include <utility>

namespace tinsmith {

std::string_view toString(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Usage: return "usage error";
    case ErrorKind::Input: return "input error";
    case ErrorKind::Geometry: return "geometry error";
    case ErrorKind::Io: return "i/o error";
    case ErrorKind::NotImplemented: return "not implemented";
    case ErrorKind::Internal: return "internal error";
  }
  return "error";
}

bool SourceLocation::empty() const {
  return file.empty() && layer.empty() && !feature && !line;
}

std::string SourceLocation::str() const {
  std::string out;
  auto append = [&out](const std::string& part) {
    if (!out.empty()) out += ", ";
    out += part;
  };
  if (!file.empty()) append(file);
  if (!layer.empty()) append("layer '" + layer + "'");
  if (feature) append("feature " + std::to_string(*feature));
  if (line) append("line " + std::to_string(*line));
  return out;
}

namespace {
std::string composeMessage(const std::string& problem, const SourceLocation& where,
                           const std::string& hint) {
  std::string message;
  if (!where.empty()) message = where.str() + ": ";
  message += problem;
  if (!hint.empty()) message += " — " + hint;
  return message;
}
}  // namespace

Error::Error(ErrorKind kind, std::string problem, SourceLocation where, std::string hint)
    : std::runtime_error(composeMessage(problem, where, hint)),
      kind_(kind),
      problem_(std::move(problem)),
      where_(std::move(where)),
      hint_(std::move(hint)) {}

Error usageError(std::string problem, std::string hint) {
  return {ErrorKind::Usage, std::move(problem), {}, std::move(hint)};
}
Error inputError(std::string problem, SourceLocation where, std::string hint) {
  return {ErrorKind::Input, std::move(problem), std::move(where), std::move(hint)};
}
Error geometryError(std::string problem, SourceLocation where, std::string hint) {
  return {ErrorKind::Geometry, std::move(problem), std::move(where), std::move(hint)};
}
Error ioError(std::string problem, SourceLocation where, std::string hint) {
  return {ErrorKind::Io, std::move(problem), std::move(where), std::move(hint)};
}
Error notImplemented(std::string what) {
  return {ErrorKind::NotImplemented, std::move(what) + " is not implemented yet", {}, {}};
}
Error internalError(std::string problem) {
  return {ErrorKind::Internal, std::move(problem), {},
          "this is a bug in tinsmith; please report it with the input that caused it"};
}

}  // namespace tinsmith
