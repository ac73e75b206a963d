// `tinsmith build`: the whole job from a config: ingest → TIN → tiles → store.
//   tinsmith build CONFIG.toml [-o STORE] [--tolerance M …] [--threads N] [--resume] [-q] [--json]
// The store is -o, else the config's [tiles] output; the tile options are the
// config's [tiles] keys, each flag given overriding its key. The TIN is kept
// beside the store as STEM.tin (out/site.3dtiles → out/site.tin), for query,
// export and tiling again with other options: the store is the same bytes as
// `tinsmith tin CONFIG -o STEM.tin` then `tinsmith tile STEM.tin -o STORE`
// with the same options.
//
// Outputs are atomic: the config, the options and the output folder are
// checked before any work; the TIN is written as STEM.partial.tin and renamed
// to STEM.tin once the store is complete, so a failed run leaves neither
// under its name (an archive's STEM.partial.3dtiles staging stays, for
// --resume; the TIN is built again on resume, the same bytes).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "core/base/error.hpp"
#include "ingest/build/from_ingest.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/output_paths.hpp"
#include "tools/cli/progress_bar.hpp"
#include "tools/cli/tile_options.hpp"
#include "tools/cli/tile_summary.hpp"

namespace tinsmith::cli {

namespace {

namespace fs = std::filesystem;

struct BuildCliOptions {
  std::string config;
  std::string output;
  TileFlags flags;
};

/// The TIN kept beside a store: out/site.3dtiles and out/site/ → out/site.tin.
fs::path tinBesideStore(fs::path store) {
  if (!store.has_filename()) store = store.parent_path();
  return store.replace_extension(".tin");
}

/// The bar's progress with every stage name prefixed ("1/2 TIN readers.ogr"),
/// so it says which part of the job runs; no callback when there is no bar.
ingest::Progress prefixed(const TerminalProgress& bar, const std::string& prefix) {
  ingest::Progress p;
  if (const ingest::Progress* inner = bar.get()) {
    p.callback = [inner, prefix](std::string_view stage, std::string_view detail,
                                 std::uint64_t done, std::uint64_t total) {
      inner->report(prefix + std::string(stage), detail, done, total);
    };
  }
  return p;
}

/// The TIN beside the store replaces only a .tin file (one from an earlier
/// build): anything else there is the user's and stays.
void requireTinOrNothing(const fs::path& tin) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(tin, ec))) return;
  constexpr std::string_view kMagic("\x89TIN\r\n\x1a\n", 8);
  std::string head(kMagic.size(), '\0');
  std::ifstream in(tin, std::ios::binary);
  const bool isTin = fs::is_regular_file(tin, ec) && in.read(head.data(), head.size()) &&
                     head == kMagic;
  if (!isTin)
    throw ioError("is in the way of the TIN written beside the tile store, and is not a .tin file",
                  fileLocation(tin), "move it away, or name the store otherwise");
}

void run(const BuildCliOptions& o) {
  const ingest::ProjectConfig config = ingest::loadProjectConfig(o.config);
  const ingest::TileJobOptions tileOptions = withTileFlags(config.tiles.job, o.flags);
  fs::path store = o.output;
  if (store.empty()) store = config.tiles.output;
  if (store.empty()) {
    SourceLocation where = fileLocation(config.file.filename());
    if (config.tiles.configLine > 0) where.line = config.tiles.configLine;
    throw Error(ErrorKind::Usage, "no tile store to write: no [tiles] output and no -o", where,
                "add output = \"NAME.3dtiles\" to [tiles], or give -o NAME.3dtiles");
  }
  const fs::path tinPath = tinBesideStore(store);
  if (tinPath.lexically_normal() == store.lexically_normal()) {
    throw usageError(
        "the tile store '" + store.string() + "' has the name of the TIN written beside it",
        "name the store NAME.3dtiles (an archive) or a folder without .tin");
  }
  fs::path partialTin = tinPath;
  partialTin.replace_extension(".partial.tin");
  checkOutputDirectory(store, "the tile store");
  store::requireReplaceable(store);
  requireTinOrNothing(tinPath);
  // The project CRS and geoid must place tiles on the globe: checked now, not
  // after the TIN is built.
  (void)ingest::ProjGeoReference(config.crs, tileOptions.geoid);

  const TileFlags& f = o.flags;
  auto bar = terminalProgress(f.quiet || f.json);
  ingest::BuildOptions tinOptions = ingest::buildOptionsFrom(config);
  tinOptions.threads = static_cast<unsigned>(tileOptions.threads);
  const ingest::Progress tinProgress = prefixed(bar, "1/2 TIN ");
  const ingest::Progress tileProgress = prefixed(bar, "2/2 tiles ");
  ingest::BuildReport report;
  ingest::TileJobSummary tiles;
  try {
    report = ingest::buildTinFromConfig(
        config, tinOptions, [&](const Mesh& mesh) { ingest::writeTinFile(partialTin, mesh); },
        bar.get() ? &tinProgress : nullptr);
    // Read back, so the tiles see exactly what `tinsmith tile STEM.tin` would.
    const TinData tin = ingest::readTinFile(partialTin);
    tiles = ingest::runTileJob(tin, tinPath.string(), store, tileOptions,
                               bar.get() ? &tileProgress : nullptr);
  } catch (...) {
    std::error_code ec;
    fs::remove(partialTin, ec);
    throw;
  }
  bar.bar.reset();
  std::error_code ec;
  fs::rename(partialTin, tinPath, ec);
  if (ec) {
    throw ioError("cannot rename " + partialTin.string() + " to " + tinPath.filename().string() +
                      ": " + ec.message(),
                  fileLocation(tinPath), "the store is complete; rename the TIN by hand");
  }

  if (f.json) {
    nlohmann::ordered_json j;
    j["config"] = config.file.string();
    j["tin"] = {{"output", tinPath.string()},
                {"report", nlohmann::ordered_json::parse(report.toJson())}};
    j["tiles"] = tileSummaryObject(tiles, store.string());
    std::cout << j.dump(2) << "\n";
    std::cerr << missedToleranceText(tiles);
  } else if (!f.quiet) {
    std::cerr << report.summary() << "wrote " << tinPath.string() << "\n";
    reportTileJob(tiles, store.string(), false, false);
  } else {
    std::cerr << missedToleranceText(tiles);
  }
  requireWithinTolerance(tiles, f.strict);
}

}  // namespace

void addBuildCommand(CLI::App& app) {
  auto opt = std::make_shared<BuildCliOptions>();
  auto* cmd =
      app.add_subcommand("build", "Run the whole job from a config: ingest → TIN → tiles → store");
  cmd->add_option("config", opt->config, "Project config (TOML), see config/README.md")->required();
  addOutputOption(*cmd, opt->output,
                  "Tile store to write, a .3dtiles archive or a directory (default: [tiles] "
                  "output). The TIN is kept beside it as STEM.tin");
  addTileFlags(*cmd, opt->flags, true);
  cmd->footer(
      "The store is the same bytes as `tinsmith tin CONFIG -o STEM.tin` then `tinsmith tile "
      "STEM.tin -o STORE` with the same options. --threads applies to the TIN and the tiles; "
      "--resume keeps the tiles of an interrupted run (the TIN is built again).\n\n" +
      app.get_footer());
  cmd->callback([opt] { run(*opt); });
}

}  // namespace tinsmith::cli
