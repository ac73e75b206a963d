#include "ingest/base/gdal_runtime.hpp"

#include <cpl_error.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <mutex>

namespace tinsmith::ingest {

void ensureGdalReady() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    // Quiet GDAL's own stderr printing; readers check return codes and read
    // CPLGetLastErrorMsg() to build messages that name the file and feature.
    CPLSetErrorHandler(CPLQuietErrorHandler);
  });
}

std::string gdalVersionString() {
  int projMajor = 0, projMinor = 0, projPatch = 0;
  OSRGetPROJVersion(&projMajor, &projMinor, &projPatch);
  return std::string("GDAL ") + GDALVersionInfo("RELEASE_NAME") + ", PROJ " +
         std::to_string(projMajor) + "." + std::to_string(projMinor) + "." +
         std::to_string(projPatch);
}

std::string lastGdalError() {
  const char* msg = CPLGetLastErrorMsg();
  return msg && *msg ? std::string(" (GDAL: ") + msg + ")" : std::string();
}

}  // namespace tinsmith::ingest
