// The human and JSON forms of a tiling summary, shared by tile, merge, build
// and info.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::cli {

std::string tileSummaryText(const ingest::TileJobSummary& s);
/// The warning for tiles over their zoom's tolerance (the worst five named);
/// empty when there are none.
std::string missedToleranceText(const ingest::TileJobSummary& s);
/// The JSON object; tileSummaryJson is its text (2-space indent, newline).
nlohmann::ordered_json tileSummaryObject(const ingest::TileJobSummary& s,
                                         const std::string& output);
std::string tileSummaryJson(const ingest::TileJobSummary& s, const std::string& output);

}  // namespace tinsmith::cli
