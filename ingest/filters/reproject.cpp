#include "ingest/filters/reproject.hpp"

#include <cpl_error.h>
#include <ogr_spatialref.h>

#include <array>
#include <atomic>
#include <memory>
#include <optional>
#include <vector>

#include "core/base/error.hpp"
#include "core/base/parallel.hpp"
#include "ingest/base/gdal_runtime.hpp"

namespace tinsmith::ingest {
namespace {

OGRSpatialReference makeSrs(const std::string& crs, const SourceLocation& where, const char* role) {
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(crs.c_str()) != OGRERR_NONE) {
    throw inputError(
        std::string(role) + " CRS '" + crs.substr(0, 80) + "' is not one GDAL/PROJ knows", where,
        "write it as \"EPSG:code\" or as WKT");
  }
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

}  // namespace

CrsTransform::CrsTransform(const std::string& source, const std::string& target,
                           const SourceLocation& where) {
  ensureGdalReady();
  if (source.empty()) {
    throw inputError("has no CRS", where,
                     "set crs = \"EPSG:…\" in the layer to say which CRS its coordinates are in");
  }
  auto src = makeSrs(source, where, "the layer's");
  auto dst = makeSrs(target, where, "the project's");
  if (src.IsSame(&dst)) return;
  CPLErrorReset();
  auto* ct = OGRCreateCoordinateTransformation(&src, &dst);
  if (!ct) {
    const char* msg = CPLGetLastErrorMsg();
    throw inputError("cannot transform from '" + source.substr(0, 80) + "' to '" +
                         target.substr(0, 80) + "'" +
                         (msg && *msg ? std::string(" (PROJ: ") + msg + ")" : std::string()),
                     where, "check the layer's CRS");
  }
  transform_ = ct;
}

CrsTransform::~CrsTransform() {
  if (transform_)
    OGRCoordinateTransformation::DestroyCT(static_cast<OGRCoordinateTransformation*>(transform_));
}

std::int64_t CrsTransform::transform(Point3* points, std::size_t count) const {
  if (!transform_) return -1;
  auto* ct = static_cast<OGRCoordinateTransformation*>(transform_);
  constexpr std::size_t kChunk = 4096;
  std::array<double, kChunk> xs{};
  std::array<double, kChunk> ys{};
  std::array<int, kChunk> ok{};
  for (std::size_t start = 0; start < count; start += kChunk) {
    const std::size_t n = std::min(kChunk, count - start);
    for (std::size_t i = 0; i < n; ++i) {
      xs[i] = points[start + i].x;
      ys[i] = points[start + i].y;
    }
    ct->Transform(n, xs.data(), ys.data(), nullptr, ok.data());
    for (std::size_t i = 0; i < n; ++i) {
      if (!ok[i] || !std::isfinite(xs[i]) || !std::isfinite(ys[i]))
        return static_cast<std::int64_t>(start + i);
      points[start + i].x = xs[i];
      points[start + i].y = ys[i];
    }
  }
  return -1;
}

void reprojectLayer(IngestedLayer& layer, const std::string& targetCrs, const Progress* progress) {
  const auto where = layerLocation(layer.config);
  const CrsTransform check(layer.crs, targetCrs, where);
  if (check.identity()) {
    layer.crs = targetCrs;
    return;
  }
  // Work units of about kBatch vertices: runs of points, or runs of features.
  struct Unit {
    bool points;
    std::size_t begin, end;
  };
  constexpr std::size_t kBatch = 65536;
  std::vector<Unit> units;
  for (std::size_t b = 0; b < layer.points.size(); b += kBatch) {
    units.push_back({true, b, std::min(b + kBatch, layer.points.size())});
  }
  for (std::size_t b = 0; b < layer.features.size();) {
    std::size_t e = b, vertices = 0;
    while (e < layer.features.size() && vertices < kBatch)
      vertices += layer.features[e++].vertices.size();
    units.push_back({false, b, e});
    b = e;
  }
  struct Failure {
    std::int64_t fid = 0;
    Point3 at;
  };
  std::vector<std::optional<Failure>> failures(units.size());
  std::atomic<std::size_t> next{0};
  // Each thread makes its own transformation: PROJ objects are not shared
  // between threads.
  auto work = [&] {
    const CrsTransform transform(layer.crs, targetCrs, where);
    for (std::size_t u = next++; u < units.size(); u = next++) {
      const Unit& unit = units[u];
      if (unit.points) {
        const auto bad =
            transform.transform(layer.points.data() + unit.begin, unit.end - unit.begin);
        if (bad >= 0) {
          const auto i = unit.begin + static_cast<std::size_t>(bad);
          failures[u] = Failure{layer.pointIds[i], layer.points[i]};
        }
        continue;
      }
      for (std::size_t f = unit.begin; f < unit.end && !failures[u]; ++f) {
        auto& v = layer.features[f].vertices;
        const auto bad = transform.transform(v.data(), v.size());
        if (bad >= 0)
          failures[u] = Failure{layer.features[f].fid, v[static_cast<std::size_t>(bad)]};
      }
    }
  };
  const std::string detail = layer.config.name;
  const auto total = static_cast<std::uint64_t>(layer.vertexCount());
  reportProgress(progress, "filters.reproject", detail, 0, total);
  runWorkers(std::min<unsigned>({resolveThreads(0), 8u, static_cast<unsigned>(units.size())}), work);
  for (const auto& failure : failures) {
    if (!failure) continue;
    throw inputError("cannot be transformed into the project CRS " + targetCrs + " (point " +
                         std::to_string(failure->at.x) + ", " + std::to_string(failure->at.y) + ")",
                     layerLocation(layer.config, failure->fid),
                     "check the layer's CRS: the point is outside its domain");
  }
  layer.crs = targetCrs;
  reportProgress(progress, "filters.reproject", detail, total, total);
}

}  // namespace tinsmith::ingest
