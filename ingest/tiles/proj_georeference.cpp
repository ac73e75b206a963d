#include "ingest/tiles/proj_georeference.hpp"

#include <ogr_spatialref.h>
#include <proj.h>

#include <atomic>
#include <memory>
#include <unordered_map>
#include <vector>

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

std::string wkt2(const OGRSpatialReference& srs) {
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  srs.exportToWkt(&wkt, options);
  std::string text = wkt ? wkt : "";
  CPLFree(wkt);
  return text;
}

/// "EPSG:26912" for the horizontal part of a compound CRS, else its name.
std::string horizontalName(const OGRSpatialReference& compound) {
  OGRSpatialReference horizontal(compound);
  horizontal.StripVertical();
  const char* authority = horizontal.GetAuthorityName(nullptr);
  const char* code = horizontal.GetAuthorityCode(nullptr);
  if (authority && code) return std::string(authority) + ":" + code;
  return horizontal.GetName() ? horizontal.GetName() : "its horizontal CRS";
}

template <typename T, void (*Free)(T*)>
struct ProjDeleter {
  void operator()(T* p) const { Free(p); }
};
void destroyContext(PJ_CONTEXT* c) {
  proj_context_destroy(c);
}
void destroyPj(PJ* p) {
  proj_destroy(p);
}
void destroyList(PJ_OBJ_LIST* l) {
  proj_list_destroy(l);
}
void destroyFactory(PJ_OPERATION_FACTORY_CONTEXT* f) {
  proj_operation_factory_context_destroy(f);
}
using Context = std::unique_ptr<PJ_CONTEXT, ProjDeleter<PJ_CONTEXT, destroyContext>>;
using Object = std::unique_ptr<PJ, ProjDeleter<PJ, destroyPj>>;
using ObjectList = std::unique_ptr<PJ_OBJ_LIST, ProjDeleter<PJ_OBJ_LIST, destroyList>>;
using Factory = std::unique_ptr<PJ_OPERATION_FACTORY_CONTEXT,
                                ProjDeleter<PJ_OPERATION_FACTORY_CONTEXT, destroyFactory>>;

/// Throws inputError unless PROJ can really convert the heights of `srs` (a
/// CRS with a vertical datum) to WGS84 ellipsoidal heights on this machine.
///
/// Why: when the geoid grid a vertical datum needs is missing, PROJ does not
/// fail; it falls back to a "ballpark vertical transformation" that leaves
/// the heights as they are, tens of metres off. So: among the operations PROJ
/// knows from `srs` to EPSG:4979, one must have every grid it uses installed
/// and not be such a ballpark. If none has, the error names the grids the
/// best one (PROJ's order) misses.
void checkHeightsConvert(const OGRSpatialReference& srs, const std::string& crs) {
  const Context ctx(proj_context_create());
  // Missing grids are what this looks for: PROJ's own complaints would only
  // clutter stderr before the error that names them.
  proj_log_func(ctx.get(), nullptr, [](void*, int, const char*) {});
  const Object src(proj_create(ctx.get(), wkt2(srs).c_str()));
  const Object dst(proj_create(ctx.get(), "EPSG:4979"));
  const Factory factory(proj_create_operation_factory_context(ctx.get(), nullptr));
  if (!src || !dst || !factory) throw inputError("PROJ cannot read the CRS '" + crs + "'");
  proj_operation_factory_context_set_grid_availability_use(ctx.get(), factory.get(),
                                                           PROJ_GRID_AVAILABILITY_USED_FOR_SORTING);
  proj_operation_factory_context_set_spatial_criterion(ctx.get(), factory.get(),
                                                       PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  const ObjectList ops(proj_create_operations(ctx.get(), src.get(), dst.get(), factory.get()));
  const int count = ops ? proj_list_get_count(ops.get()) : 0;
  std::vector<std::string> missing;  // of the best operation that converts heights
  for (int i = 0; i < count; ++i) {
    const Object op(proj_list_get(ctx.get(), ops.get(), i));
    const char* name = op ? proj_get_name(op.get()) : nullptr;
    // PROJ names the no-op fallback "… (ballpark vertical transformation, …)".
    if (!name || std::string_view(name).find("ballpark vertical") != std::string_view::npos)
      continue;
    std::vector<std::string> absent;
    const int grids = proj_coordoperation_get_grid_used_count(ctx.get(), op.get());
    for (int g = 0; g < grids; ++g) {
      const char *shortName = nullptr, *fullName = nullptr, *package = nullptr, *url = nullptr;
      int directDownload = 0, openLicense = 0, available = 0;
      proj_coordoperation_get_grid_used(ctx.get(), op.get(), g, &shortName, &fullName, &package,
                                        &url, &directDownload, &openLicense, &available);
      if (!available) absent.emplace_back(shortName ? shortName : "?");
    }
    if (absent.empty()) return;
    if (missing.empty()) missing = std::move(absent);
  }
  const std::string datum =
      srs.GetAttrValue("VERT_DATUM") ? srs.GetAttrValue("VERT_DATUM") : "its vertical datum";
  const std::string approximation =
      "or, as an approximation, set the CRS to " + horizontalName(srs) +
      " alone with geoid = \"egm96\" ([tiles] geoid or --geoid; orthometric heights are "
      "within a metre or two of EGM96 in most places)";
  if (missing.empty()) {
    throw inputError("PROJ knows no way to turn heights in '" + crs + "' (" + datum +
                         ") into ellipsoidal heights",
                     {}, approximation);
  }
  std::string names, urls;
  for (const auto& m : missing) {
    names += (names.empty() ? "" : ", ") + m;
    urls += (urls.empty() ? "" : " ") + ("https://cdn.proj.org/" + m);
  }
  throw inputError("PROJ needs the grid " + names + " to turn heights in '" + crs + "' (" + datum +
                       ") into ellipsoidal heights, and it is not installed on this machine",
                   {},
                   "install it: download " + urls +
                       " into /usr/share/proj (or ~/.local/share/proj); " + approximation);
}

}  // namespace

void requireTinCrs(const std::string& crs, const std::string& tinName) {
  if (crs.empty())
    throw inputError("the TIN has no CRS, so its tiles cannot be placed on the globe",
                     tinName.empty() ? SourceLocation{} : fileLocation(tinName),
                     "build it again with one: tinsmith tin … --crs EPSG:… (e.g. EPSG:32612 for "
                     "UTM 12N), or a config's project.crs; --frame local needs one too");
}

ProjGeoReference::ProjGeoReference(std::string crs, std::string geoid)
    : crs_(std::move(crs)), geoid_(std::move(geoid)), serial_(nextSerial++) {
  ensureGdalReady();
  requireTinCrs(crs_);
  const OGRSpatialReference given = source(crs_, crs_);
  if (geoid_.empty()) {
    sourceDefinition_ = crs_;
    if (given.IsCompound()) checkHeightsConvert(given, crs_);
  } else if (geoid_ == "egm96") {
    if (given.IsCompound()) {
      throw usageError("the TIN's CRS '" + crs_ +
                           "' has a vertical datum of its own, so geoid = \"egm96\" would "
                           "contradict it",
                       "leave geoid out (PROJ converts the CRS's heights), or give the "
                       "horizontal CRS alone (" +
                           horizontalName(given) + ") with geoid = \"egm96\"");
    }
    // A compound CRS: horizontal as given, EGM96 heights (EPSG:5773).
    OGRSpatialReference vertical;
    vertical.importFromEPSG(5773);
    OGRSpatialReference compound;
    if (compound.SetCompoundCS("tin + EGM96 height", &given, &vertical) != OGRERR_NONE) {
      throw inputError("cannot combine the TIN's CRS '" + crs_ + "' with EGM96 heights");
    }
    checkHeightsConvert(compound, crs_ + " + EGM96 height");
    sourceDefinition_ = wkt2(compound);
  } else {
    throw usageError("unknown geoid '" + geoid_ + "'",
                     "use geoid = \"egm96\" or leave it out (ellipsoidal heights)");
  }
  (void)forThisThread();  // fail now, not on a worker
}

ProjGeoReference::~ProjGeoReference() = default;

ProjGeoReference::Transform& ProjGeoReference::forThisThread() const {
  // GDAL keeps each thread's PROJ context in a thread_local of its own, made
  // on the thread's first PROJ call. Thread-locals die in the reverse order
  // of their making, so that context is made here, before `transforms`, and
  // outlives it: the transformations below need it when they are destroyed
  // at the thread's exit, and made after it, GDAL would make a fresh context
  // there that nothing frees (LeakSanitizer: 512 bytes a thread from
  // proj_context_create).
  thread_local const bool projContextFirst = [] {
    OGRSpatialReference wgs84;
    return wgs84.importFromEPSG(4326) == OGRERR_NONE;
  }();
  (void)projContextFirst;
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
