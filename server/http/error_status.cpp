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

std::string errorBodyJson(int status, ErrorKind kind, const std::string& message) {
  nlohmann::json body;
  body["error"] = {{"status", status}, {"kind", std::string(toString(kind))}, {"message", message}};
  return body.dump();
}

}  // namespace tinsmith::server
