// The seam between the ingest front half (pipeline/load_layers.hpp) and the
// TIN builder: IngestedLayers → BuildLayers, and the ingest stages' counts
// and timings into the BuildReport.
#pragma once

#include <functional>
#include <vector>

#include "ingest/build/build_report.hpp"
#include "ingest/build/tin_builder.hpp"
#include "ingest/pipeline/load_layers.hpp"

namespace tinsmith::ingest {

/// One BuildLayer per ingested layer, config order. Interior rings of a
/// boundary polygon become holes; every line's source names the file, the
/// layer and the feature id (and part, for multi-geometries). Takes the
/// layers by value: pass them with std::move to hand the coordinates over
/// without a copy (they are the bulk of the memory of a big build).
std::vector<BuildLayer> toBuildLayers(std::vector<IngestedLayer> layers);

/// Adds the ingest result's layer counts, cleaning counts, contour-crossing
/// data errors and stage timings to `report` (before the builder's own).
void addIngestReport(BuildReport& report, const IngestResult& ingest);

/// BuildOptions from the config's [tin] table and project CRS.
BuildOptions buildOptionsFrom(const ProjectConfig& config);

/// A config's TIN, as `tinsmith tin CONFIG` and `tinsmith build` make it:
/// every layer read, reprojected and cleaned (loadLayers), then
/// buildTinInto(…, options, consume, progress), with the ingest stages'
/// counts and timings added to the report. `options` normally start from
/// buildOptionsFrom(config). Throws what those throw.
BuildReport buildTinFromConfig(const ProjectConfig& config, const BuildOptions& options,
                               const std::function<void(const Mesh&)>& consume,
                               const Progress* progress = nullptr);

}  // namespace tinsmith::ingest
