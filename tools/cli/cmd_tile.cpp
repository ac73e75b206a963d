// `tinsmith tile`: cut a TIN into level-of-detail 3D Tiles (Draco glTF).
//   tinsmith tile SITE.tin -o SITE.3dtiles [--tolerance M] [--threads N] [--resume]
//   tinsmith tile SITE.tin -o PART.3dtiles --subtree Z/X/Y     (one shard)
//   tinsmith tile SITE.tin -o TOP.3dtiles --until-zoom Z       (the tiles above the shards)
//   tinsmith merge TOP.3dtiles PART*.3dtiles -o SITE.3dtiles
// A summary goes to stderr (or JSON to stdout with --json); a progress bar
// when stderr is a terminal.
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/progress_bar.hpp"
#include "tools/cli/tile_summary.hpp"

namespace tinsmith::cli {

namespace {

struct TileCliOptions {
  std::string tin;
  std::string output;
  double tolerance = 1.0;
  std::size_t maxTriangles = 32768;
  std::optional<int> maxZoom;
  double lambda = 0.01;
  std::string compression = "draco";
  std::string frame = "ecef";
  std::string geoid;
  std::string subtree;
  std::optional<int> untilZoom;
  bool resume = false;
  int threads = 0;
  bool quiet = false;
  bool json = false;
};

struct MergeCliOptions {
  std::vector<std::string> inputs;
  std::string output;
  bool json = false;
  bool quiet = false;
};

void report(const ingest::TileJobSummary& summary, const std::string& output, bool json,
            bool quiet) {
  if (json) {
    std::cout << tileSummaryJson(summary, output);
  } else if (!quiet) {
    std::cerr << "wrote " << output << "\n" << tileSummaryText(summary);
  }
}

/// The job's options from the command line; throws usageError for a value
/// no option takes.
ingest::TileJobOptions tileJobOptions(const TileCliOptions& c) {
  ingest::TileJobOptions o;
  o.tiler.tolerance = c.tolerance;
  o.tiler.maxTriangles = c.maxTriangles;
  o.tiler.maxZoom = c.maxZoom;
  o.tiler.lambdaFactor = c.lambda;
  if (c.compression == "draco") {
    o.compression = encode::Compression::Draco;
  } else if (c.compression == "none") {
    o.compression = encode::Compression::None;
  } else {
    throw usageError("--compression must be draco or none (got '" + c.compression + "')");
  }
  if (c.frame == "ecef") {
    o.frame = tiles::ContentFrame::Ecef;
  } else if (c.frame == "local") {
    o.frame = tiles::ContentFrame::Local;
  } else {
    throw usageError("--frame must be ecef or local (got '" + c.frame + "')");
  }
  o.geoid = c.geoid;
  if (!c.subtree.empty()) o.subtree = tiles::parseTileId(c.subtree, "--subtree");
  o.untilZoom = c.untilZoom;
  if (o.untilZoom && *o.untilZoom < 1) throw usageError("--until-zoom must be 1 or more");
  if (o.subtree && o.untilZoom)
    throw usageError("--subtree and --until-zoom make different shards: give one");
  if (c.threads < 0) throw usageError("--threads must be 0 (all cores) or more");
  o.threads = c.threads;
  o.resume = c.resume;
  return o;
}

}  // namespace

void addTileCommand(CLI::App& app) {
  auto opt = std::make_shared<TileCliOptions>();
  auto* cmd = app.add_subcommand("tile", "Cut a TIN into level-of-detail 3D Tiles (Draco glTF)");
  cmd->add_option("tin", opt->tin, "The .tin file to tile")->required();
  cmd->add_option("-o,--output", opt->output, "Tile store: a .3dtiles archive, or a directory")
      ->required();
  cmd->add_option("--tolerance", opt->tolerance,
                  "Metres the finest zoom meets against the TIN (default 1)");
  cmd->add_option("--max-triangles", opt->maxTriangles,
                  "Triangles a tile may hold, about (default 32768)");
  cmd->add_option("--max-zoom", opt->maxZoom,
                  "Deepest tile zoom (default: the planned finest zoom + 6)");
  cmd->add_option("--lambda", opt->lambda,
                  "Smoothing λ of the zoom and tile fits as a multiple of λ_d (default 0.01)");
  cmd->add_option("--compression", opt->compression, "draco (default) or none");
  cmd->add_option("--frame", opt->frame,
                  "ecef (3D Tiles on the globe, default) or local (ENU metres)");
  cmd->add_option("--geoid", opt->geoid,
                  "egm96: the TIN's z are EGM96 heights (default: ellipsoidal)");
  cmd->add_option("--subtree", opt->subtree,
                  "Build only this tile and its descendants (Z/X/Y): a shard");
  cmd->add_option("--until-zoom", opt->untilZoom,
                  "Build only the tiles above this zoom: the shards' top");
  cmd->add_option("--threads", opt->threads,
                  "Worker threads (default 0: all cores); same bytes for any");
  cmd->add_flag("--resume", opt->resume,
                "Keep tiles already in the store and build only the missing ones");
  cmd->add_flag("-q,--quiet", opt->quiet, "No summary, no progress bar");
  cmd->add_flag("--json", opt->json, "Print the summary as JSON on stdout");
  cmd->callback([opt] {
    const ingest::TileJobOptions o = tileJobOptions(*opt);
    const TinData tin = ingest::readTinFile(opt->tin);
    auto bar = terminalProgress(opt->quiet || opt->json);
    const auto summary = ingest::runTileJob(tin, opt->tin, opt->output, o, bar.get());
    bar.bar.reset();
    report(summary, opt->output, opt->json, opt->quiet);
  });

  auto merge = std::make_shared<MergeCliOptions>();
  auto* mcmd = app.add_subcommand("merge", "Join tile stores built as shards of one job into one");
  mcmd->add_option("stores", merge->inputs,
                   "Shard stores (from tinsmith tile --subtree / --until-zoom)")
      ->required();
  mcmd->add_option("-o,--output", merge->output, "The joined store (.3dtiles or a directory)")
      ->required();
  mcmd->add_flag("-q,--quiet", merge->quiet, "No summary");
  mcmd->add_flag("--json", merge->json, "Print the summary as JSON on stdout");
  mcmd->callback([merge] {
    std::vector<std::filesystem::path> inputs(merge->inputs.begin(), merge->inputs.end());
    const auto summary = ingest::mergeTileStores(inputs, merge->output);
    report(summary, merge->output, merge->json, merge->quiet);
  });
}

}  // namespace tinsmith::cli
