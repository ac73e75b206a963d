#include "tools/cli/tile_options.hpp"

#include <iostream>

#include "core/base/error.hpp"
#include "tools/cli/exit_codes.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/slurm_jobs.hpp"
#include "tools/cli/tile_summary.hpp"

namespace tinsmith::cli {

void addTileFlags(CLI::App& cmd, TileFlags& flags, bool fromConfig) {
  // "(default 1)", or for build "(default: [tiles] tolerance, else 1)".
  auto dflt = [fromConfig](const std::string& key, const std::string& value) {
    return fromConfig ? " (default: [tiles] " + key + ", else " + value + ")"
                      : " (default " + value + ")";
  };
  cmd.add_option("--tolerance", flags.tolerance,
                 "Metres the finest zoom meets against the TIN" + dflt("tolerance", "1"));
  cmd.add_option("--max-triangles", flags.maxTriangles,
                 "Triangles a tile may hold, about" + dflt("max_triangles", "32768"));
  cmd.add_option("--max-zoom", flags.maxZoom,
                 "Deepest tile zoom" + dflt("max_zoom", "the planned finest zoom + 6"));
  cmd.add_option(
      "--lambda", flags.lambda,
      "Smoothing λ of the zoom and tile fits as a multiple of λ_d" + dflt("lambda", "0.01"));
  cmd.add_option("--compression", flags.compression,
                 "draco or none" + dflt("compression", "draco"));
  cmd.add_option("--frame", flags.frame,
                 "ecef (3D Tiles on the globe) or local (ENU metres)" + dflt("frame", "ecef"));
  cmd.add_option("--geoid", flags.geoid,
                 "egm96: the TIN's z are EGM96 heights; \"\": ellipsoidal" + dflt("geoid", "\"\""));
  cmd.add_option("--scheme", flags.scheme,
                 "3d-tiles (tileset.json), quantized-mesh (Cesium terrain: terrain/layer.json) or "
                 "both in one store" + dflt("scheme", "3d-tiles"));
  cmd.add_option("--attribution", flags.attribution,
                 "Cesium terrain's credit line (layer.json)" + dflt("attribution", "\"Terrain: tinsmith\""));
  addThreadsOption(cmd, flags.threads, "Worker threads", "the same bytes for any count");
  cmd.add_flag("--resume", flags.resume,
               "Keep tiles already in the store (finished, or its .partial stage from a stopped run) "
               "and build only the missing ones");
  cmd.add_flag("--strict", flags.strict,
               "Exit with code 1 (the store is still written) when a tile's measured error is "
               "over its zoom's tolerance");
  addQuietFlag(cmd, flags.quiet, "No summary, no progress bar");
  addJsonFlag(cmd, flags.json, "Print the summary as JSON on stdout");
}

ingest::TileJobOptions withTileFlags(ingest::TileJobOptions o, const TileFlags& flags) {
  if (flags.tolerance) o.tiler.tolerance = *flags.tolerance;
  if (flags.maxTriangles) o.tiler.maxTriangles = *flags.maxTriangles;
  if (flags.maxZoom) o.tiler.maxZoom = *flags.maxZoom;
  if (flags.lambda) o.tiler.lambdaFactor = *flags.lambda;
  if (flags.compression) {
    const auto c = ingest::parseCompression(*flags.compression);
    if (!c)
      throw usageError("--compression must be draco or none (got '" + *flags.compression + "')");
    o.compression = *c;
  }
  if (flags.frame) {
    const auto f = ingest::parseContentFrame(*flags.frame);
    if (!f) throw usageError("--frame must be ecef or local (got '" + *flags.frame + "')");
    o.frame = *f;
  }
  if (flags.geoid) o.geoid = *flags.geoid;
  if (flags.scheme) {
    const auto sc = ingest::parseTileScheme(*flags.scheme);
    if (!sc)
      throw usageError("--scheme must be 3d-tiles, quantized-mesh or both (got '" + *flags.scheme +
                       "')");
    o.scheme = *sc;
  }
  if (flags.attribution) o.attribution = *flags.attribution;
  o.threads = flags.threads;
  o.resume = flags.resume;
  ingest::checkTileJobOptions(o);
  return o;
}

void reportTileJob(ingest::TileJobSummary summary, const std::string& output, bool json,
                   bool quiet) {
  const ProcessCost cost = processCost();
  summary.cpuSeconds = cost.cpuSeconds;
  summary.peakMemoryBytes = static_cast<std::size_t>(cost.peakMegabytes * 1e6);
  if (json) {
    std::cout << tileSummaryJson(summary, output);
  } else if (!quiet) {
    std::cerr << "wrote " << output << "\n" << tileSummaryText(summary);
  }
  std::cerr << missedToleranceText(summary);
}

void requireWithinTolerance(const ingest::TileJobSummary& summary, bool strict) {
  if (strict && (!summary.missed.empty() || (summary.terrain && !summary.terrain->missed.empty())))
    throw CheckFailed{};
}

}  // namespace tinsmith::cli
