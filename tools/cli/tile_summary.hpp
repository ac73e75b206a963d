// The human and JSON forms of a tiling summary, shared by tile, merge, build
// and info.
#pragma once

#include <optional>
#include <string>

#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::cli {

std::string tileSummaryText(const ingest::TileJobSummary& s);
std::string tileSummaryJson(const ingest::TileJobSummary& s, const std::string& output);

/// The tiling options from their command-line (or config) forms; throws
/// usageError for an unknown compression or frame.
ingest::TileJobOptions tileJobOptions(double tolerance, std::size_t maxTriangles,
                                      std::optional<int> maxZoom, double lambda,
                                      const std::string& compression, const std::string& frame,
                                      const std::string& geoid);

}  // namespace tinsmith::cli
