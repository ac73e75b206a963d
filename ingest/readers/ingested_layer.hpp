// The layer model the TIN builder consumes: what each [[layer]] of the config
// became after reading (readers.*), reprojection (filters.reproject) and
// cleaning (filters.clean).
//
// Contract of an IngestedLayer handed out by loadLayers():
//   * every coordinate is in the project CRS (`crs`): x, y projected metres;
//     z in metres, or NaN where the source had no z (hasZ == false: 2D roads,
//     rivers, lakes, boundaries and holes — the builder drapes them);
//   * point kinds (points, dem) fill `points` + `pointIds`; line and area kinds
//     fill `features`, never both;
//   * a feature is ONE polyline or ring: multi-geometries are split into parts
//     (same fid, part = 0, 1, …) and polygons into rings (ring 0 the exterior,
//     1… the interiors). A ring is stored without its closing vertex and has
//     closed == true; a line is closed when its ends coincided in the source.
//     Ring orientation is as in the source (not normalised);
//   * after cleaning: no two consecutive vertices of a feature closer than the
//     snap tolerance, lines have >= 2 vertices and rings >= 3; no two points of
//     the point layers closer than the snap tolerance (across layers too);
//     no contour crosses itself or a contour of another z (crossing segments
//     are cut out, see filters/clean.hpp) — unless strict mode threw instead.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/base/point.hpp"
#include "core/tin/tin_data.hpp"
#include "ingest/config/project_config.hpp"

namespace tinsmith::ingest {

struct IngestedFeature {
  std::int64_t fid = 0;   ///< OGR feature id (for messages); text files: 1-based line
  std::int32_t part = 0;  ///< part index inside a multi-geometry
  std::int32_t ring = 0;  ///< polygon ring: 0 exterior, 1… interiors; 0 for lines
  bool closed = false;    ///< last vertex connects back to the first (not repeated)
  bool hasZ = false;      ///< false: z is NaN, to be draped
  std::vector<Point3> vertices;
};

struct IngestedLayer {
  LayerConfig config;
  FeatureKind kind = FeatureKind::Other;
  std::string sourceCrs;  ///< the CRS the data was read in (WKT or "EPSG:n"); empty if none
  std::string crs;        ///< the CRS the coordinates are in now
  bool hasZ = false;      ///< all vertices carry a real z
  std::vector<IngestedFeature> features;  ///< line and area kinds
  std::vector<Point3> points;             ///< point kinds (points, dem)
  std::vector<std::int64_t> pointIds;  ///< per point: fid, text line, or raster cell row*width+col
  std::uint64_t nullGeometriesSkipped = 0;  ///< features without geometry (not an error)

  [[nodiscard]] std::size_t vertexCount() const {
    std::size_t n = points.size();
    for (const auto& f : features) n += f.vertices.size();
    return n;
  }
};

/// "contours.gpkg, layer 'contours'" — where-prefix for messages about a layer.
SourceLocation layerLocation(const LayerConfig& config,
                             std::optional<std::int64_t> fid = std::nullopt);

}  // namespace tinsmith::ingest
