// The human and JSON forms of a tiling summary, shared by tile, merge and
// info.
#pragma once

#include <string>

#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::cli {

std::string tileSummaryText(const ingest::TileJobSummary& s);
std::string tileSummaryJson(const ingest::TileJobSummary& s, const std::string& output);

}  // namespace tinsmith::cli
