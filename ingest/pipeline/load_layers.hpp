// The ingest front half in one call: every [[layer]] of a project config is
// read (readers.*), moved into the project CRS (filters.reproject) and
// cleaned (filters.clean). The TIN builder takes IngestResult::layers; the
// CLI prints `summaries`, `cleaning` and `timings`.
//
// Contract of the result: see ingested_layer.hpp (coordinates in result.crs,
// cleaned as filters/clean.hpp describes). Layers keep config order.
// Throws tinsmith::Error as the readers, reprojection and cleaning do (kind
// Input for bad data, naming file, layer, feature and line).
#pragma once

#include <string>
#include <vector>

#include "ingest/base/progress.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/filters/clean.hpp"
#include "ingest/readers/ingested_layer.hpp"

namespace tinsmith::ingest {

/// Counts for one layer, before and after cleaning.
struct LayerSummary {
  std::string name;
  LayerKind kind = LayerKind::Points;
  std::string sourceCrs;  ///< the CRS the layer was read in
  std::uint64_t featuresRead = 0, verticesRead = 0, pointsRead = 0;
  std::uint64_t featuresKept = 0, verticesKept = 0, pointsKept = 0;
  std::uint64_t nullGeometriesSkipped = 0;
  bool hasZ = false;
};

/// Wall-clock seconds of one stage ("readers", "filters.reproject", "filters.clean").
struct StageTiming {
  std::string stage;
  double seconds = 0.0;
};

struct IngestResult {
  std::string crs;  ///< the project CRS
  std::vector<IngestedLayer> layers;
  CleaningReport cleaning;
  std::vector<LayerSummary> summaries;
  std::vector<StageTiming> timings;
};

/// Reads, reprojects and cleans every layer of `config` (tolerance and strict
/// mode from config.tin). `progress` may be null.
IngestResult loadLayers(const ProjectConfig& config, const Progress* progress = nullptr);

/// The stages one at a time, for tools and benchmarks that time them apart.
std::vector<IngestedLayer> readLayers(const ProjectConfig& config,
                                      const Progress* progress = nullptr);
void reprojectLayers(std::vector<IngestedLayer>& layers, const std::string& crs,
                     const Progress* progress = nullptr);

}  // namespace tinsmith::ingest
