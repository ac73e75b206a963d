// The one place where tinsmith::Error kinds become HTTP statuses and JSON
// error bodies. Routes throw tinsmith::Error; the server's handler calls this.
#pragma once

#include <string>

#include "core/base/error.hpp"
#include "server/http/message.hpp"

namespace tinsmith::server {

/// Usage and Input → 400, NotImplemented → 501, everything else → 500.
int httpStatusFor(ErrorKind kind);

/// {"error": {"status": 400, "kind": "input error", "message": "..."}}, with
/// "parameter" when one is named (the query parameter or body field at fault).
std::string errorBodyJson(int status, ErrorKind kind, const std::string& message,
                          const std::string& parameter = {});

/// A response carrying that body: Content-Type application/json,
/// Cache-Control no-store.
Response errorResponse(int status, ErrorKind kind, const std::string& message,
                       const std::string& parameter = {});

}  // namespace tinsmith::server
