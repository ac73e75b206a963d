// The one place where tinsmith::Error kinds become HTTP statuses and JSON
// error bodies. Routes throw tinsmith::Error; the server's handler calls this.
#pragma once

#include <string>

#include "core/base/error.hpp"

namespace tinsmith::server {

/// Usage and Input → 400, NotImplemented → 501, everything else → 500.
int httpStatusFor(ErrorKind kind);

/// {"error": {"status": 400, "kind": "input error", "message": "..."}}
std::string errorBodyJson(int status, ErrorKind kind, const std::string& message);

}  // namespace tinsmith::server
