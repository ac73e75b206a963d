// `tinsmith tile`: cut a TIN into level-of-detail 3D Tiles (Draco glTF).
//   tinsmith tile SITE.tin -o SITE.3dtiles [--tolerance M] [--threads N] [--resume]
//   tinsmith tile SITE.tin -o PART.3dtiles --subtree Z/X/Y     (one shard)
//       [--plan tiler.plan --unchecked-ancestors]   (reads only its square of the TIN)
//   tinsmith tile SITE.tin -o TOP.3dtiles --until-zoom Z       (the tiles above the shards;
//       over 2^18 vertices only from the mosaic zoom K down: merge builds those above K)
//       [--write-plan tiler.plan]          (and the plan the subtree shards take)
//   tinsmith merge TOP.3dtiles PART*.3dtiles -o SITE.3dtiles
//   tinsmith tile SITE.tin -o SITE.3dtiles --store-until-zoom Z (deeper tiles
//                                                 for serve --on-demand)
// A summary goes to stderr (or JSON to stdout with --json); a progress bar
// when stderr is a terminal.
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/progress_bar.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/tile_options.hpp"

namespace tinsmith::cli {

namespace {

struct TileCliOptions {
  std::string tin;
  std::string output;
  TileFlags flags;
  std::string subtree;
  std::optional<int> untilZoom;
  std::optional<int> storeUntilZoom;
  std::optional<int> finestZoom;
  bool emptyOk = false;
  bool uncheckedAncestors = false;
  std::string plan;
  std::string writePlan;
};

struct MergeCliOptions {
  std::vector<std::string> inputs;
  std::string output;
  bool json = false;
  bool quiet = false;
  bool strict = false;
  int threads = 0;
};

}  // namespace

void addTileCommand(CLI::App& app) {
  auto opt = std::make_shared<TileCliOptions>();
  auto* cmd = app.add_subcommand("tile", "Cut a TIN into level-of-detail 3D Tiles (Draco glTF)");
  cmd->add_option("tin", opt->tin, "The .tin file to tile")->required();
  addOutputOption(*cmd, opt->output, "Tile store: a .3dtiles archive, or a directory")->required();
  addTileFlags(*cmd, opt->flags, false);
  cmd->add_option("--subtree", opt->subtree,
                  "Build only this tile and its descendants (Z/X/Y): a shard");
  cmd->add_flag("--empty-ok", opt->emptyOk,
                "With --subtree: a subtree that is not in the pyramid (an ancestor holds no "
                "terrain or meets the tolerance) writes nothing and exits 0 (shard arrays)");
  cmd->add_flag("--unchecked-ancestors", opt->uncheckedAncestors,
                "With --subtree: do not build the subtree's ancestors to check that it is in the "
                "pyramid; the shard is written in any case, and merge drops it when it is not "
                "(shard arrays)");
  cmd->add_option("--until-zoom", opt->untilZoom,
                  "Build only the tiles above this zoom: the shards' top (over 2^18 TIN "
                  "vertices, not above the mosaic zoom: tinsmith merge builds those)");
  cmd->add_option("--store-until-zoom", opt->storeUntilZoom,
                  "Plan every tile (tileset.json lists them all) but store only those above "
                  "this zoom (and always those above the mosaic zoom of a TIN of over 2^18 "
                  "vertices); tinsmith serve --on-demand builds the rest from the store's TIN");
  cmd->add_option("--finest-zoom", opt->finestZoom,
                  "The finest zoom the job's plan chose (tinsmith slurm gives it to every shard): "
                  "skips the planning fit; another value than the planning's builds another "
                  "pyramid, which merge refuses to join with this job's shards");
  cmd->add_option("--plan", opt->plan,
                  "The job's tiling plan (tiler.plan in tinsmith slurm's --workdir): the pyramid, "
                  "the finest zoom and the simplified lines are taken from it, and with --subtree "
                  "--unchecked-ancestors only the subtree's part of the TIN is read");
  cmd->add_option("--write-plan", opt->writePlan,
                  "With --until-zoom: also write the job's tiling plan here, before the tiles "
                  "(what tinsmith slurm's subtree shards read with --plan)");
  cmd->callback([opt] {
    ingest::TileJobOptions o;
    o.tiler.plannedFinestZoom = opt->finestZoom;
    o.storeUntilZoom = opt->storeUntilZoom;
    if (!opt->subtree.empty()) o.subtree = tiles::parseTileId(opt->subtree, "--subtree");
    o.untilZoom = opt->untilZoom;
    if (!opt->writePlan.empty()) o.writePlan = opt->writePlan;
    if (opt->emptyOk && !o.subtree) throw usageError("--empty-ok goes with --subtree");
    o.subtreeMayBeEmpty = opt->emptyOk;
    o.uncheckedAncestors = opt->uncheckedAncestors;
    o = withTileFlags(o, opt->flags);
    if (!opt->plan.empty())
      o.plan = std::make_shared<const ingest::TilingPlan>(ingest::readTilingPlan(opt->plan));
    // A shard below the root reads only its square of the TIN.
    TinData tin;
    if (o.plan && o.subtree && o.subtree->z > 0 && o.uncheckedAncestors) {
      ingest::requireCurrentTinFormat(opt->tin);
      const tiles::Rect square = o.plan->tiler.geometry.bounds(*o.subtree);
      ingest::TinPart part =
          ingest::readTinFilePart(opt->tin, tiles::tilerReadRegion(square),
                                  tiles::tilerVertexRegion(o.plan->tiler, square));
      o.partOf = ingest::TinIdentity{part.fileCrc, part.vertices, part.triangles};
      if (!opt->flags.quiet && !opt->flags.json) {
        const auto megabytes = [](std::uint64_t bytes) { return static_cast<double>(bytes) / 1e6; };
        std::cerr << std::fixed << std::setprecision(1) << "read the part of " << opt->tin
                  << " around tile " << o.subtree->name() << ": " << part.tin.vertices.size()
                  << " of " << part.vertices << " vertices, " << part.tin.triangles.size() << " of "
                  << part.triangles << " triangles, " << megabytes(part.bytesRead) << " of "
                  << megabytes(std::filesystem::file_size(opt->tin)) << " MB\n"
                  << std::defaultfloat;
      }
      tin = std::move(part.tin);
    } else {
      tin = ingest::readTinFile(opt->tin);
    }
    const TileFlags& f = opt->flags;
    auto bar = terminalProgress(f.quiet || f.json);
    const auto summary = ingest::runTileJob(tin, opt->tin, opt->output, o, bar.get());
    bar.bar.reset();
    if (!summary.notInPyramid.empty()) {
      if (f.json)
        std::cout
            << nlohmann::json{{"output", nullptr}, {"notInPyramid", summary.notInPyramid}}.dump(2)
            << "\n";
      else if (!f.quiet)
        std::cerr << summary.notInPyramid << ": nothing to build, " << opt->output
                  << " not written\n";
      return;
    }
    reportTileJob(summary, opt->output, f.json, f.quiet);
    requireWithinTolerance(summary, f.strict);
  });

  auto merge = std::make_shared<MergeCliOptions>();
  auto* mcmd = app.add_subcommand("merge", "Join tile stores built as shards of one job into one");
  mcmd->add_option("stores", merge->inputs,
                   "Shard stores (from tinsmith tile --subtree / --until-zoom)")
      ->required();
  addOutputOption(*mcmd, merge->output, "The joined store (.3dtiles or a directory)")->required();
  addQuietFlag(*mcmd, merge->quiet, "No summary");
  addJsonFlag(*mcmd, merge->json, "Print the summary as JSON on stdout");
  mcmd->add_flag("--strict", merge->strict,
                 "Exit with code 1 (the store is still written) when a tile's measured error is "
                 "over its zoom's tolerance");
  addThreadsOption(*mcmd, merge->threads,
                   "Worker threads for the tiles above the mosaic zoom, which the merge builds "
                   "from the shards' zoom-K tiles over 2^18 TIN vertices");
  mcmd->callback([merge] {
    std::vector<std::filesystem::path> inputs(merge->inputs.begin(), merge->inputs.end());
    auto bar = terminalProgress(merge->quiet || merge->json);
    const auto summary = ingest::mergeTileStores(inputs, merge->output, merge->threads, bar.get());
    bar.bar.reset();
    reportTileJob(summary, merge->output, merge->json, merge->quiet);
    requireWithinTolerance(summary, merge->strict);
  });
}

}  // namespace tinsmith::cli
