#include "server/http/error_status.hpp"

#include <nlohmann/json.hpp>

namespace tinsmith::server {

int httpStatusFor(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Usage:
    case ErrorKind::Input: return 400;
    case ErrorKind::NotImplemented: return 501;
    case ErrorKind::Geometry:
    case ErrorKind::Io:
    case ErrorKind::Internal: return 500;
  }
  return 500;
}

std::string errorBodyJson(int status, ErrorKind kind, const std::string& message,
                          const std::string& parameter) {
  nlohmann::json body;
  body["error"] = {{"status", status}, {"kind", std::string(toString(kind))}, {"message", message}};
  if (!parameter.empty()) body["error"]["parameter"] = parameter;
  // Messages may quote what a client sent: replace invalid UTF-8 rather than throw.
  return body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

Response errorResponse(int status, ErrorKind kind, const std::string& message,
                       const std::string& parameter) {
  Response r;
  r.status = status;
  r.addHeader("Content-Type", "application/json");
  r.addHeader("Cache-Control", "no-store");
  r.setBody(errorBodyJson(status, kind, message, parameter) + "\n");
  return r;
}

}  // namespace tinsmith::server
