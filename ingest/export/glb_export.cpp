// The whole-TIN .glb; see glb_export.hpp.
#include "ingest/export/glb_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/base/error.hpp"
#include "core/encode/frames.hpp"
#include "core/encode/mesh_buffers.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::ingest {
namespace {

// Without --max-position-error, Draco's quantization gets at least this much
// of the bound (m) on a TIN whose float32 rounding alone nears the default.
constexpr double kMinimumQuantizationShare = 0.001;

std::string metres(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g m", m);
  return buf;
}

/// The TIN's vertices in the export frame, and the origin positions are
/// taken relative to.
struct FramedVertices {
  std::vector<Point3> points;
  Point3 origin;
};

FramedVertices ecefVertices(const TinData& tin, const std::string& geoid,
                            std::string_view tinName) {
  const std::string name(tinName);
  if (tin.crs.empty()) {
    throw inputError("the TIN has no CRS, so --frame ecef cannot place it on the globe",
                     fileLocation(name),
                     "rebuild it with one (tinsmith tin … --crs EPSG:…), or export with --frame "
                     "local (x, y, z as they are)");
  }
  // Heights are metres on the globe: a CRS in feet is refused, as by `tile`.
  checkProjectCrs(tin.crs, "the CRS of " + name);
  const ProjGeoReference geo(tin.crs, geoid);
  std::vector<encode::Geodetic> geodetic(tin.vertices.size());
  geo.toGeodetic(tin.vertices, geodetic);
  FramedVertices out;
  out.points.reserve(geodetic.size());
  for (const auto& g : geodetic) out.points.push_back(encode::geodeticToEcef(g));
  out.origin = encode::boundingBox(out.points).centre();
  return out;
}

FramedVertices localVertices(const TinData& tin) {
  // A whole-metre offset, so a user can type it back (a DCC scene's origin,
  // a georeferencing add-on) and the positions stay near the origin.
  const Point3 c = encode::boundingBox(tin.vertices).centre();
  return {tin.vertices, {std::round(c.x), std::round(c.y), std::round(c.z)}};
}

std::string assetExtras(const TinData& tin, const GlbExportOptions& options, const GlbExport& out) {
  const bool ecef = options.frame == GlbFrame::Ecef;
  nlohmann::ordered_json j = {{"frame", ecef ? "ecef" : "local"}, {"crs", tin.crs}};
  if (ecef) {
    j["geoid"] = options.geoid;
  } else {
    j["offset"] = {out.origin.x, out.origin.y, out.origin.z};
  }
  j.update({{"vertices", out.vertices},
            {"triangles", out.triangles},
            {"positionErrorBound", out.positionErrorBound}});
  return nlohmann::ordered_json{{"tinsmith", j}}.dump();
}

}  // namespace

std::optional<GlbFrame> parseGlbFrame(std::string_view name) {
  if (name == "ecef") return GlbFrame::Ecef;
  if (name == "local") return GlbFrame::Local;
  return std::nullopt;
}

void checkGlbExportOptions(const GlbExportOptions& options) {
  if (!isKnownGeoid(options.geoid)) {
    throw usageError("unknown geoid '" + options.geoid + "'",
                     "use --geoid egm96 (z are EGM96 heights) or leave it out (ellipsoidal)");
  }
  if (!options.geoid.empty() && options.frame == GlbFrame::Local) {
    throw usageError("--geoid places heights on the globe, which --frame local does not",
                     "leave --geoid out, or use --frame ecef");
  }
  if (options.maxPositionError &&
      (!(*options.maxPositionError > 0) || !std::isfinite(*options.maxPositionError))) {
    throw usageError("--max-position-error must be a positive number of metres",
                     "e.g. --max-position-error 0.001");
  }
}

GlbExport exportGlb(const TinData& tin, const GlbExportOptions& options, std::string_view tinName) {
  checkGlbExportOptions(options);
  if (tin.triangles.empty()) {
    throw inputError("the TIN has no triangles, so there is no surface to export",
                     fileLocation(std::string(tinName)),
                     "build it from at least three points that are not on one line");
  }
  const FramedVertices framed = options.frame == GlbFrame::Ecef
                                    ? ecefVertices(tin, options.geoid, tinName)
                                    : localVertices(tin);
  const std::vector<Point3> normals = encode::areaWeightedNormals(framed.points, tin.triangles);
  const encode::MeshBuffers buffers =
      encode::meshBuffersAround(framed.points, normals, tin.triangles, framed.origin);

  // Float32 positions round once when written (plain: all there is); Draco's
  // float arithmetic adds its own rounding, then its quantization takes the
  // rest of the bound.
  const bool draco = options.compression == encode::Compression::Draco;
  const double written = encode::floatRoundingBound(framed.points, framed.origin);
  const double floatShare = written + (draco ? encode::dracoArithmeticBound(buffers) : 0.0);
  const double bound = options.maxPositionError.value_or(
      std::max(kDefaultGlbPositionError, floatShare + kMinimumQuantizationShare));
  if (draco && !(bound > floatShare)) {
    throw usageError("--max-position-error " + metres(bound) +
                         " is tighter than Draco's float32 positions can hold on this TIN "
                         "(their rounding alone may reach " +
                         metres(floatShare) + ")",
                     "give at least --max-position-error " +
                         metres(floatShare + kMinimumQuantizationShare) +
                         ", or --compression none");
  }

  GlbExport out;
  out.vertices = tin.vertices.size();
  out.triangles = tin.triangles.size();
  out.origin = framed.origin;
  encode::GlbOptions glb;
  glb.compression = options.compression;
  glb.maxPositionError = bound - floatShare;
  // The declared bound is the requested one (what the user relies on, as a
  // tile's record does); the quantization never takes more than its share of
  // it (checked below).
  out.positionErrorBound = draco ? bound : written;
  glb.assetExtras = assetExtras(tin, options, out);
  encode::GlbResult result;
  try {
    // Local: the offset stays in asset.extras, not in the node, so a DCC tool
    // opens the mesh near its origin; the matrix is only the y-up turn.
    const Point3 nodeOrigin = options.frame == GlbFrame::Ecef ? framed.origin : Point3{};
    result = encode::encodeGlb(buffers, encode::zUpContentRootMatrix(nodeOrigin), glb);
  } catch (const Error& e) {
    throw Error(e.kind(), e.problem(), fileLocation(std::string(tinName)), e.hint());
  }
  if (draco && result.positionErrorBound > glb.maxPositionError) {
    throw usageError("--max-position-error " + metres(bound) +
                         " needs finer than Draco's 30-bit quantization on this TIN",
                     "give at least --max-position-error " +
                         metres(floatShare + result.positionErrorBound) +
                         ", or --compression none");
  }
  out.positionBits = result.positionBits;
  out.bytes = std::move(result.bytes);
  return out;
}

GlbExport writeGlb(const std::filesystem::path& path, const TinData& tin,
                   const GlbExportOptions& options, std::string_view tinName) {
  checkGlbExportOptions(options);
  // The temp file first: an unwritable folder fails before the encoding.
  AtomicFile file(path);
  GlbExport out = exportGlb(tin, options, tinName);
  file.write(out.bytes);
  file.commit();
  return out;
}

}  // namespace tinsmith::ingest
