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
//   7. validation — BuildOptions::validation: the mesh's structure by default
//      in release builds, the full validator (Cdt::validate()) in debug
//      builds and on request; a failure is an internalError.
// The flat-triangle repair and the validation work on the CDT's mesh: buildTin
// makes its TinData once, at the end, and buildTinInto makes none.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/base/point.hpp"
#include "core/mesh/mesh.hpp"
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

/// How much of the validator runs on the result (stage 7).
enum class BuildValidation : std::uint8_t {
  Off,
  /// validate(mesh) without the Delaunay check: finite coordinates, every
  /// triangle strictly counter-clockwise (exact), twin symmetry, constraint
  /// features equal on both sides and known, boundary loops and Euler
  /// characteristic. Linear, a small share of the build.
  Structural,
  /// Cdt::validate(): the above, plus every unconstrained interior edge
  /// locally Delaunay (exact incircle), every input point a vertex or reported
  /// merged, every constraint segment a chain of edges carrying its feature.
  /// Costly: 1.7 s CPU and per-vertex adjacency lists on top of a 6 s build of
  /// 1.1 M vertices (the ingest benchmark), against 0.6 s for Structural.
  Full,
};

/// Full in debug builds (NDEBUG not defined when the library was built), as
/// the design asks of the validator; Structural in release builds.
BuildValidation defaultBuildValidation();

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
  BuildValidation validation = defaultBuildValidation();
  unsigned threads = 0;  ///< for the triangulation and its check; 0 = every core (same TIN for any value)
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

/// The same build for callers that only write the TIN out (`tinsmith tin`):
/// `consume` gets the CDT's mesh before the CDT is freed — e.g.
/// writeTinFile(path, mesh), which writes the bytes writeTinFile(path,
/// buildTin(…).tin) would — so the mesh and a TinData copy of it are never in
/// memory together. Returns the report (complete before `consume` runs); what
/// buildTin throws, and whatever `consume` throws, propagates.
BuildReport buildTinInto(std::vector<BuildLayer> layers, const BuildOptions& options,
                         const std::function<void(const Mesh&)>& consume,
                         const Progress* progress = nullptr);

/// Where each layer kind goes: true for kinds that take lines (contours,
/// roads, rivers, lakes, boundary, holes).
bool takesLines(FeatureKind kind);

}  // namespace tinsmith::ingest
