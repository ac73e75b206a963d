// What the TIN builder did, for the human summary on stderr and for
// `tinsmith tin --report report.json`. Plain data; toJson() and summary()
// render the same content.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/base/point.hpp"
#include "ingest/tinfile/tin_counts.hpp"

namespace tinsmith::ingest {

/// The TinCounts part describes the TIN built.
struct BuildReport : TinCounts {
  struct Layer {
    std::string name;
    std::string kind;    ///< as in the config: contours, points, road, …
    std::string source;  ///< file (and layer)
    std::size_t features = 0;
    std::size_t points = 0;    ///< point geometries (spot heights, raster cells)
    std::size_t vertices = 0;  ///< polyline and ring vertices
    std::size_t readFeatures = 0;  ///< as read, before cleaning (0: not known)
    std::size_t readVertices = 0;  ///< points and vertices as read, before cleaning
    std::string sourceCrs;         ///< the CRS the layer was read in
  };
  struct Event {         ///< a merge, crossing or bridge candidate
    Point2 at;
    std::string what;    ///< e.g. "road.geojson, feature 0 × streams.geojson, feature 3"
    double zKept = 0, zOther = 0;
  };
  struct Lake {
    std::string source;
    double level = 0;    ///< metres: the fixed shore level
    std::size_t vertices = 0;
  };
  struct StageTime {
    std::string stage;
    double seconds = 0;
  };

  std::string crs;
  std::vector<Layer> layers;
  /// Cleaning done by the ingest stage (readers, filters), counter by name.
  std::vector<std::pair<std::string, std::size_t>> cleaning;
  /// Data errors found (e.g. crossing contours), as messages.
  std::vector<std::string> dataErrors;

  std::size_t inputPoints = 0;          ///< points handed to the triangulation
  std::size_t inputLineVertices = 0;    ///< constraint vertices handed to it
  std::size_t mergedPoints = 0;         ///< merged by the snap tolerance
  std::size_t crossings = 0;            ///< constraint crossings split
  std::size_t droppedSegments = 0;      ///< zero-length segments dropped
  std::size_t droppedOutside = 0;       ///< input outside the boundary, dropped
  std::vector<Event> bridgeCandidates;  ///< road × river crossings
  std::vector<Event> mergeSamples;      ///< first few merges with conflicting z

  std::size_t riversDraped = 0, riversChecked = 0, riversReversed = 0;
  std::size_t riverVerticesAdjusted = 0;
  double riverMaxAdjustment = 0;
  /// Per river changed by at least kRiverChangeToReport: its largest change
  /// (zOther before, zKept after), largest first. A river lowered metres
  /// below the surface it runs on leaves a pit in the TIN beside banks that
  /// keep their height (a reservoir, weir or culvert the layers do not hold).
  std::vector<Event> riverLargestChanges;
  static constexpr double kRiverChangeToReport = 1.0;
  std::size_t roadsDraped = 0, roadSpikesRemoved = 0;
  double roadMaxChange = 0;
  std::vector<Lake> lakes;
  std::size_t drapedOutside = 0;  ///< draped vertices off the surface (z interpolated)

  bool flatRepair = false;
  std::size_t flatBefore = 0, flatAfter = 0, flatVerticesAdded = 0, flatIterations = 0;
  std::size_t flatRegions = 0, flatClosedRegions = 0;

  bool valid = false;
  std::string validation;  ///< what was checked: "structural", "full" or "off"
  std::vector<std::string> validationProblems;

  std::vector<StageTime> times;
  double totalSeconds = 0;

  /// Pretty-printed JSON (2-space indent) with every field above.
  [[nodiscard]] std::string toJson() const;
  /// A readable multi-line summary for stderr.
  [[nodiscard]] std::string summary() const;
};

}  // namespace tinsmith::ingest
