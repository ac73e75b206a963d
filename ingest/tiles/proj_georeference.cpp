#include "ingest/tiles/proj_georeference.hpp"

#include <ogr_spatialref.h>

#include <atomic>
#include <unordered_map>

#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"

namespace tinsmith::ingest {

struct ProjGeoReference::Transform {
  OGRCoordinateTransformation* ct = nullptr;
  ~Transform() {
    if (ct) OGRCoordinateTransformation::DestroyCT(ct);
  }
};

namespace {

std::atomic<std::uint64_t> nextSerial{1};

OGRSpatialReference source(const std::string& definition, const std::string& crs) {
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(definition.c_str()) != OGRERR_NONE) {
    throw inputError("the TIN's CRS '" + crs + "' is not one PROJ knows", {},
                     "give the TIN a CRS such as EPSG:26912 (tinsmith tin --crs)");
  }
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

OGRCoordinateTransformation* makeTransform(const std::string& definition, const std::string& crs) {
  OGRSpatialReference src = source(definition, crs);
  OGRSpatialReference dst;
  dst.importFromEPSG(4979);
  dst.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  auto* ct = OGRCreateCoordinateTransformation(&src, &dst);
  if (!ct) {
    throw inputError("PROJ cannot transform the TIN's CRS '" + crs + "' to WGS84 (EPSG:4979)", {},
                     "check the CRS, and that proj-data is installed for a geoid");
  }
  return ct;
}

}  // namespace

ProjGeoReference::ProjGeoReference(std::string crs, std::string geoid)
    : crs_(std::move(crs)), geoid_(std::move(geoid)), serial_(nextSerial++) {
  ensureGdalReady();
  if (crs_.empty()) {
    throw inputError(
        "the TIN has no CRS, so its tiles cannot be placed on the globe", {},
        "rebuild it with a CRS (tinsmith tin --crs EPSG:…); --frame local needs one too");
  }
  if (geoid_.empty()) {
    sourceDefinition_ = crs_;
  } else if (geoid_ == "egm96") {
    // A compound CRS: horizontal as given, EGM96 heights (EPSG:5773).
    OGRSpatialReference horizontal = source(crs_, crs_);
    OGRSpatialReference vertical;
    vertical.importFromEPSG(5773);
    OGRSpatialReference compound;
    if (compound.SetCompoundCS("tin + EGM96 height", &horizontal, &vertical) != OGRERR_NONE) {
      throw inputError("cannot combine the TIN's CRS '" + crs_ + "' with EGM96 heights");
    }
    char* wkt = nullptr;
    const char* options[] = {"FORMAT=WKT2_2019", nullptr};
    compound.exportToWkt(&wkt, options);
    sourceDefinition_ = wkt ? wkt : "";
    CPLFree(wkt);
  } else {
    throw usageError("unknown geoid '" + geoid_ + "'",
                     "use geoid = \"egm96\" or leave it out (ellipsoidal heights)");
  }
  (void)forThisThread();  // fail now, not on a worker
}

ProjGeoReference::~ProjGeoReference() = default;

ProjGeoReference::Transform& ProjGeoReference::forThisThread() const {
  thread_local std::unordered_map<std::uint64_t, std::unique_ptr<Transform>> transforms;
  auto& slot = transforms[serial_];
  if (!slot) {
    slot = std::make_unique<Transform>();
    slot->ct = makeTransform(sourceDefinition_, crs_);
  }
  return *slot;
}

void ProjGeoReference::toGeodetic(std::span<const Point3> in,
                                  std::span<encode::Geodetic> out) const {
  Transform& t = forThisThread();
  std::vector<double> x(in.size()), y(in.size()), z(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    x[i] = in[i].x;
    y[i] = in[i].y;
    z[i] = in[i].z;
  }
  std::vector<int> ok(in.size(), 0);
  if (!in.empty() &&
      !t.ct->Transform(in.size(), x.data(), y.data(), z.data(), nullptr, ok.data())) {
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (!ok[i]) {
        throw inputError(
            "PROJ could not transform the point (" + std::to_string(in[i].x) + ", " +
                std::to_string(in[i].y) + ") from " + crs_ + " to WGS84",
            {}, "check that the TIN's CRS is right and that the point is inside its area of use");
      }
    }
  }
  for (std::size_t i = 0; i < in.size(); ++i) out[i] = {x[i], y[i], z[i]};
}

}  // namespace tinsmith::ingest
