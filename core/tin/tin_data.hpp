// TinData: the plain, indexed form of a terrain TIN that stages hand to each
// other — the CDT produces it, the .tin file stores it (ingest/), the fitter
// and the tiler read it. Contract:
//   * vertices: x, y in `crs` (projected, metres), z in metres;
//   * triangles: vertex indices, counter-clockwise in x, y, no degenerate ones;
//   * constrainedEdges: one entry per (edge, feature) pair, a < b; an edge that
//     several features share (overlapping constraints) appears once per feature;
//   * features: what each input feature was; a feature id indexes this vector.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/base/point.hpp"

namespace tinsmith {

/// What an input feature is. Order does not matter; see constraintPriority().
enum class FeatureKind : std::uint8_t {
  Other = 0,   ///< anything without a role (plain break lines, CLI input)
  SpotHeight,  ///< scattered surveyed points
  Contour,
  Road,
  River,
  Lake,        ///< a lake shore: a flat, closed constraint
  Boundary,    ///< the outer boundary of the TIN's domain
  Hole,        ///< a void: triangles inside are removed
  Raster,      ///< points from a DEM layer
  BreakLine,   ///< a break line without a named role (`tinsmith tin --breaklines`)
};

/// When constraints cross or points merge, z comes from the feature with the
/// higher priority: river > road > lake > break line > contour > spot height
/// > everything else. A line's z therefore wins over a point it passes through.
constexpr int constraintPriority(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::River: return 6;
    case FeatureKind::Road: return 5;
    case FeatureKind::Lake: return 4;
    case FeatureKind::BreakLine: return 3;
    case FeatureKind::Contour: return 2;
    case FeatureKind::SpotHeight: return 1;
    default: return 0;
  }
}

/// Where a feature came from, for messages and reports.
struct TinFeature {
  FeatureKind kind = FeatureKind::Other;
  std::string source;  ///< e.g. "road.geojson, feature 0"
};

struct TinData {
  using Triangle = std::array<std::uint32_t, 3>;
  struct ConstrainedEdge {
    std::uint32_t a = 0;
    std::uint32_t b = 0;
    std::uint32_t feature = 0;  ///< index into `features`
    friend bool operator==(const ConstrainedEdge&, const ConstrainedEdge&) = default;
  };

  std::string crs;  ///< "EPSG:26912", or WKT; empty when unknown
  std::vector<Point3> vertices;
  std::vector<Triangle> triangles;
  std::vector<ConstrainedEdge> constrainedEdges;
  std::vector<TinFeature> features;
};

}  // namespace tinsmith
