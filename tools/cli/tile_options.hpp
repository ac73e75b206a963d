// The options `tinsmith tile` and `tinsmith build` share, declared once: the
// tiler's and encoder's keys (those of a config's [tiles] table), threads,
// --resume, -q and --json, and the one way both report a finished job.
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <optional>
#include <string>

#include "ingest/tiles/tile_job.hpp"

namespace tinsmith::cli {

/// As given on the command line; an unset optional was not given.
struct TileFlags {
  std::optional<double> tolerance;
  std::optional<std::size_t> maxTriangles;
  std::optional<int> maxZoom;
  std::optional<double> lambda;
  std::optional<std::string> compression, frame, geoid, scheme, attribution;
  int threads = 0;
  bool resume = false;
  bool strict = false;
  bool quiet = false;
  bool json = false;
};

/// Declares the shared options on `cmd`, writing into `flags` (which must
/// outlive the parse). With `fromConfig` the help says that an option not
/// given comes from the config's [tiles] key.
void addTileFlags(CLI::App& cmd, TileFlags& flags, bool fromConfig);

/// `base` (TileJobOptions' defaults, or a config's [tiles]) with every flag
/// that was given laid over it, checked by ingest::checkTileJobOptions.
/// Throws usageError naming the option for a value no option takes.
ingest::TileJobOptions withTileFlags(ingest::TileJobOptions base, const TileFlags& flags);

/// The summary of a finished job, with this process's CPU time and peak
/// memory: JSON on stdout with --json, else text on stderr unless -q; tiles
/// over their zoom's tolerance are warned of on stderr in any case.
void reportTileJob(ingest::TileJobSummary summary, const std::string& output, bool json,
                   bool quiet);

/// When `strict` (--strict), throws CheckFailed (exit code 1) when a tile is
/// over its zoom's tolerance; the store is written and reported first.
void requireWithinTolerance(const ingest::TileJobSummary& summary, bool strict);

}  // namespace tinsmith::cli
