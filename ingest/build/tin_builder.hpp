// builders.tin: ingested layers → constrained Delaunay TIN (core/cdt) with
// terrain rules applied, and a report of everything it changed.
//
// Stages, each timed in the report:
//   1. base surface — points, DEM cells and contours (and other 3D lines of
//      unknown role) triangulated; 2D break lines are draped on it;
//   2. lakes — each shore ring draped, and the lake made flat at a fixed level:
//      the lowest draped shore z. Points, contour and river vertices inside a
//      lake are dropped (a line is cut at its last vertex outside), so the
//      lake surface stays exactly level;
//   3. rivers — 2D rivers densified and draped; every river (3D ones too) made
//      to descend downstream (line_profile.hpp: flow from the digitised order,
//      or from the end elevations when they disagree), adjustments counted;
//   4. roads — 3D roads as they are; 2D ones densified, draped and smoothed
//      along their length (spikes removed);
//   5. triangulation — everything into one Cdt: points, contours, roads,
//      rivers and lake shores as constraints with their FeatureKind, the
//      boundary and holes as the domain. Crossings are split with z from the
//      higher-priority feature (river > road > lake > contour); road × river
//      crossings are reported as bridge candidates; crossings of two contours
//      at different levels are data errors (fatal with `strict`);
//   6. flat-triangle repair — flat_triangles.hpp, repeated until none is
//      left or no proposal helps (at most `flatPasses` passes);
//   7. validation — Cdt::validate(); a failure is an internalError.
#pragma once

#include <string>
#include <vector>

#include "core/base/point.hpp"
#include "core/tin/tin_data.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/build/build_report.hpp"

namespace tinsmith::ingest {

struct BuildLine {
  std::vector<Point3> vertices;
  bool closed = false;  ///< a ring (lake shore, boundary, hole): last joins first
  bool hasZ = true;     ///< false: 2D, z is draped from the base surface (not for contours)
  std::string source;   ///< "streams.geojson, feature 3" — for messages and TinFeature
};

/// One layer ready for triangulation: already read, reprojected and cleaned,
/// in the project CRS.
struct BuildLayer {
  std::string name;
  std::string kindName;  ///< as in the config ("contours", "river", …), for the report
  FeatureKind kind = FeatureKind::Other;
  std::string source;    ///< the file (and layer)
  std::vector<Point3> points;   ///< point layers (SpotHeight, Raster, Other)
  std::vector<BuildLine> lines; ///< line and ring layers
};

struct BuildOptions {
  std::string crs;               ///< the project CRS, copied into the TIN
  double snapTolerance = 0.001;  ///< metres
  bool flatTriangleRepair = true;
  bool riverDescent = true;
  bool strict = false;           ///< contour crossings at different levels are fatal
  double drapeSpacing = 10.0;    ///< metres: 2D lines densified to this before draping (0: off)
  double roadWindow = 50.0;      ///< metres: road smoothing window
  double roadSpikeThreshold = 2.0;  ///< metres
  int flatPasses = 4;
  bool validate = true;
};

struct BuildResult {
  TinData tin;
  BuildReport report;
};

/// Builds the TIN. Throws tinsmith::Error: inputError for bad layers (e.g. no
/// points at all), geometryError when the input cannot be triangulated or a
/// 2D line lies off the surface, inputError for contour crossings in strict
/// mode, internalError if the result fails validation.
/// Takes the layers by value and frees their coordinates once the
/// triangulation holds them: pass them with std::move for big inputs.
BuildResult buildTin(std::vector<BuildLayer> layers, const BuildOptions& options,
                     const Progress* progress = nullptr);

/// Where each layer kind goes: true for kinds that take lines (contours,
/// roads, rivers, lakes, boundary, holes).
bool takesLines(FeatureKind kind);

}  // namespace tinsmith::ingest
