// GDAL process-wide set-up for the ingest stages: drivers registered once,
// errors routed into tinsmith::Error instead of GDAL's stderr printing.
#pragma once

#include <string>

namespace tinsmith::ingest {

/// Registers all GDAL/OGR drivers exactly once (thread-safe); call before any
/// GDAL use. Idempotent and cheap after the first call.
void ensureGdalReady();

/// GDAL's last error message as " (GDAL: …)" to append to ours, or "".
std::string lastGdalError();

/// "GDAL 3.6.2, PROJ 9.1.1" — for `tinsmith --version` and reports.
std::string gdalVersionString();

}  // namespace tinsmith::ingest
