#include "ingest/filters/reproject.hpp"

#include <cpl_error.h>
#include <ogr_spatialref.h>

#include <array>
#include <memory>

#include "core/base/error.hpp"
#include "ingest/base/gdal_runtime.hpp"

namespace tinsmith::ingest {
namespace {

OGRSpatialReference makeSrs(const std::string& crs, const SourceLocation& where, const char* role) {
  OGRSpatialReference srs;
  if (srs.SetFromUserInput(crs.c_str()) != OGRERR_NONE) {
    throw inputError(std::string(role) + " CRS '" + crs.substr(0, 80) + "' is not one GDAL/PROJ knows", where,
                     "write it as \"EPSG:code\" or as WKT");
  }
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

}  // namespace

CrsTransform::CrsTransform(const std::string& source, const std::string& target, const SourceLocation& where) {
  ensureGdalReady();
  if (source.empty()) {
    throw inputError("has no CRS", where, "set crs = \"EPSG:…\" in the layer to say which CRS its coordinates are in");
  }
  auto src = makeSrs(source, where, "the layer's");
  auto dst = makeSrs(target, where, "the project's");
  if (src.IsSame(&dst)) return;
  CPLErrorReset();
  auto* ct = OGRCreateCoordinateTransformation(&src, &dst);
  if (!ct) {
    const char* msg = CPLGetLastErrorMsg();
    throw inputError("cannot transform from '" + source.substr(0, 80) + "' to '" + target.substr(0, 80) + "'" +
                         (msg && *msg ? std::string(" (PROJ: ") + msg + ")" : std::string()),
                     where, "check the layer's CRS");
  }
  transform_ = ct;
}

CrsTransform::~CrsTransform() {
  if (transform_) OGRCoordinateTransformation::DestroyCT(static_cast<OGRCoordinateTransformation*>(transform_));
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
      if (!ok[i] || !std::isfinite(xs[i]) || !std::isfinite(ys[i])) return static_cast<std::int64_t>(start + i);
      points[start + i].x = xs[i];
      points[start + i].y = ys[i];
    }
  }
  return -1;
}

void reprojectLayer(IngestedLayer& layer, const std::string& targetCrs, const Progress* progress) {
  const CrsTransform transform(layer.crs, targetCrs, layerLocation(layer.config));
  layer.crs = targetCrs;
  if (transform.identity()) return;
  const std::string detail = layer.config.name;
  ProgressTicker ticker(progress, "filters.reproject", detail, layer.vertexCount());
  std::uint64_t done = 0;
  auto fail = [&](std::int64_t fid, const Point3& p) {
    throw inputError("cannot be transformed into the project CRS " + targetCrs + " (point " + std::to_string(p.x) +
                         ", " + std::to_string(p.y) + ")",
                     layerLocation(layer.config, fid), "check the layer's CRS: the point is outside its domain");
  };
  constexpr std::size_t kBatch = 65536;
  for (std::size_t start = 0; start < layer.points.size(); start += kBatch) {
    const std::size_t n = std::min(kBatch, layer.points.size() - start);
    const auto bad = transform.transform(layer.points.data() + start, n);
    if (bad >= 0) {
      const auto i = start + static_cast<std::size_t>(bad);
      fail(layer.pointIds[i], layer.points[i]);
    }
    done += n;
    ticker.step(done);
  }
  for (auto& f : layer.features) {
    const auto bad = transform.transform(f.vertices.data(), f.vertices.size());
    if (bad >= 0) fail(f.fid, f.vertices[static_cast<std::size_t>(bad)]);
    done += f.vertices.size();
    ticker.step(done);
  }
  ticker.finish();
}

}  // namespace tinsmith::ingest
