// filters.clean: tidy raw features before triangulation; every action counted.
//
// Rules, in the order they run (all in the project CRS, tolerance in metres):
//  1. snap: a line/area vertex within `tolerance` of a vertex of another,
//     earlier feature takes that vertex's x, y exactly (z kept), so shared
//     vertices become identical. Features are visited by constraintPriority
//     (river, road, lake, contour, …), then config order, so the higher-
//     priority feature's position wins;
//  2. repeated vertices: consecutive vertices closer than `tolerance`
//     (zero-length segments) are dropped, the first kept; for a ring also the
//     last against the first;
//  3. degenerate features: lines left with < 2 vertices, rings with < 3, are
//     dropped;
//  4. points: a point within `tolerance` of a line/area vertex is dropped (the
//     break line's vertex stays); of two points within `tolerance` of each
//     other the one from the higher-priority layer (spot heights over DEM
//     cells), else the earlier one, is kept — counted as merged, and as a z
//     conflict when their z differ by more than `zConflict`;
//  5. contour crossings: a contour crossing (or touching, away from its
//     neighbouring segments) itself, or a contour of a different z, is a data
//     error. Each is reported with both layers and feature ids; the segments
//     involved are cut out of their features (splitting them), or, with
//     `strict`, a tinsmith::Error (Input) is thrown naming the first ones.
//
// Complexity: grid hashing (GridHash) for 1–4, a segment grid for 5: O(n)
// expected for evenly spread data. Deterministic: same input, same output.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ingest/base/progress.hpp"
#include "ingest/readers/ingested_layer.hpp"

namespace tinsmith::ingest {

struct CleanOptions {
  double tolerance = 0.001;  ///< metres; 0 merges exact duplicates only
  double zConflict = 0.01;   ///< metres: merged points whose z differ more are counted as conflicts
  bool strict = false;       ///< crossing contours throw instead of being cut out
};

/// A contour crossing found by rule 5.
struct ContourCrossing {
  std::string layerA, layerB;       ///< layer names (config `name`)
  std::int64_t fidA = 0, fidB = 0;  ///< feature ids
  double zA = 0.0, zB = 0.0;
  Point2 at;          ///< where, in the project CRS
  bool self = false;  ///< a contour crossing itself (A == B)
};

struct CleaningReport {
  std::uint64_t verticesSnapped = 0;
  std::uint64_t repeatedVerticesDropped = 0;
  std::uint64_t degenerateFeaturesDropped = 0;
  std::uint64_t pointsOnBreakLineVertices = 0;
  std::uint64_t duplicatePointsMerged = 0;
  std::uint64_t duplicatePointZConflicts = 0;
  std::uint64_t contourSelfCrossings = 0;
  std::uint64_t contourCrossings = 0;  ///< between contours of different z
  std::uint64_t segmentsCutOut = 0;
  std::vector<ContourCrossing> crossings;  ///< every crossing, in a deterministic order
};

/// Applies rules 1–5 to `layers` in place and returns what was done.
CleaningReport cleanLayers(std::vector<IngestedLayer>& layers, const CleanOptions& options,
                           const Progress* progress = nullptr);

/// "contours 'elev' feature 12 (z 1600) crosses feature 40 (z 1620) at 431200.5, 4514300.25"
std::string describe(const ContourCrossing& crossing);

}  // namespace tinsmith::ingest
