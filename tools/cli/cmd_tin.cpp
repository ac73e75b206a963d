// `tinsmith tin`: build a constrained Delaunay TIN.
//   tinsmith tin CONFIG.toml -o site.tin [--report r.json] [--strict] [--validate]
//   tinsmith tin --points FILE... --breaklines FILE... -o OUT.tin [--snap T] [--crs C] [--validate]
//   tinsmith tin --points FILE... --block-points N [--max-circumradius R] -o OUT.tin
//   tinsmith tin --blocks DIR --block K     (a task of tinsmith slurm-tin)
//   tinsmith tin --blocks DIR -o OUT.tin    (its assembly)
// The first reads every [[layer]] of the config (ingest: read, reproject,
// clean) and applies the terrain rules (builders.tin); the second triangulates
// plain inputs as they are: XYZ/CSV points, and break lines as GeoJSON (or any
// OGR format) 3D (Multi)LineStrings or text polylines (x y z per line, a
// blank line between polylines); either may be a synthetic spec instead of a
// file (`--points 'synthetic:grid?nx=20&ny=20'`, readers/synthetic_reader.hpp).
// The third builds a TIN of more points than memory holds, block by block
// (ingest/build/block_tin.hpp).
// A human summary goes to stderr; progress bars too when stderr is a terminal.
// Outputs are written atomically: a failed run leaves no file behind.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/tin/hull_trim.hpp"
#include "ingest/base/atomic_file.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/build/block_tin.hpp"
#include "ingest/build/from_ingest.hpp"
#include "ingest/build/tin_builder.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/pipeline/load_layers.hpp"
#include "ingest/readers/layer_reader.hpp"
#include "ingest/readers/point_sources.hpp"
#include "ingest/readers/synthetic_reader.hpp"
#include "ingest/readers/text_points.hpp"
#include "ingest/readers/text_polylines.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/output_paths.hpp"
#include "tools/cli/progress_bar.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/slurm_jobs.hpp"

namespace tinsmith::cli {

namespace {

struct TinOptions {
  std::string config;
  std::vector<std::string> points;
  std::vector<std::string> breaklines;
  std::string output;
  std::string report;
  std::optional<double> snap;
  std::string crs;
  bool strict = false;
  bool noFlatRepair = false;
  bool fullValidation = false;
  std::optional<double> trimHull;
  std::optional<std::size_t> blockPoints;
  std::optional<double> maxCircumradius;
  std::string blocksDir;
  std::optional<std::size_t> blockTask;
  unsigned threads = 0;
  bool quiet = false;
};

bool isTextPolylineFile(const std::filesystem::path& p) {
  const auto ext = p.extension().string();
  return ext == ".txt" || ext == ".xyz" || ext == ".pl" || ext == ".poly" || ext == ".lines";
}

// Plain mode: every input as it is; points of kind Other, break lines of kind
// BreakLine, so a line keeps its z where it passes through a point.
// Each file's read time goes into `times` as the stage "read FILENAME".
std::vector<ingest::BuildLayer> plainLayers(const TinOptions& o,
                                            std::vector<ingest::BuildReport::StageTime>& times) {
  std::vector<ingest::BuildLayer> layers;
  auto start = std::chrono::steady_clock::now();
  auto timeRead = [&](const ingest::BuildLayer& layer) {
    const auto now = std::chrono::steady_clock::now();
    times.push_back({"read " + layer.name, std::chrono::duration<double>(now - start).count()});
    start = now;
  };
  for (const auto& file : o.points) {
    ingest::BuildLayer layer;
    layer.name =
        ingest::isSyntheticSpec(file) ? file : std::filesystem::path(file).filename().string();
    layer.kindName = "points";
    layer.kind = FeatureKind::Other;
    layer.source = file;
    if (ingest::isTextPointFile(file)) {
      ingest::TextPointOptions text;
      text.threads = o.threads;
      layer.points = ingest::readTextPoints(file, text);
    } else {
      layer.points = ingest::readNonTextPoints(file);
    }
    timeRead(layer);
    layers.push_back(std::move(layer));
  }
  for (const auto& file : o.breaklines) {
    ingest::BuildLayer layer;
    layer.name = std::filesystem::path(file).filename().string();
    layer.kindName = "breaklines";
    layer.kind = FeatureKind::BreakLine;
    layer.source = file;
    if (ingest::isSyntheticSpec(file)) {
      layer.name = file;
      const auto read = ingest::readSyntheticLayer(ingest::commandLineLayer(file, file, ingest::LayerKind::Road));
      for (const auto& f : read.features) {
        if (!f.hasZ)
          throw inputError("break line has no z", {file, {}, f.fid, {}},
                           "leave z=none out of the spec, or use a config to drape the lines");
        layer.lines.push_back(
            {f.vertices, f.closed, true, file + ", line " + std::to_string(f.fid)});
      }
    } else if (isTextPolylineFile(file)) {
      for (auto& pl : ingest::readTextPolylines(file))
        layer.lines.push_back({std::move(pl.vertices), pl.closed, true,
                               file + ", line " + std::to_string(pl.firstLine)});
    } else {
      // Any line kind: the lines are read as they are.
      const auto read =
          ingest::readOgrLayer(ingest::commandLineLayer(layer.name, file, ingest::LayerKind::Road));
      for (const auto& f : read.features) {
        const std::string where = file + ", feature " + std::to_string(f.fid) +
                                  (f.part > 0 ? ", part " + std::to_string(f.part) : "");
        if (!f.hasZ)
          throw inputError("break line has no z", {file, {}, f.fid, {}},
                           "give break lines 3D coordinates [x, y, z], or use a config to drape them");
        layer.lines.push_back({f.vertices, f.closed, true, where});
      }
    }
    timeRead(layer);
    layers.push_back(std::move(layer));
  }
  return layers;
}

void writeReport(const std::string& path, const ingest::BuildReport& report) {
  ingest::AtomicFile file(path);
  file.write(report.toJson());
  file.commit();
}

/// The report (--report) and the summary of a TIN built by blocks.
void finishBlockRun(const TinOptions& o, const ingest::BlockTinReport& report) {
  if (!o.report.empty()) {
    try {
      ingest::AtomicFile file(o.report);
      file.write(report.toJson());
      file.commit();
    } catch (...) {
      std::error_code ec;
      std::filesystem::remove(o.output, ec);  // both outputs or neither
      throw;
    }
  }
  if (!o.quiet) std::cerr << report.summary() << "wrote " << o.output << "\n";
}

// --block-points: the TIN built block by block (ingest/build/block_tin.hpp).
void runByBlocks(const TinOptions& o) {
  if (!o.config.empty() || !o.breaklines.empty() || o.points.empty())
    throw usageError("--block-points builds a TIN of --points only",
                     "give the points with --points; break lines need the whole TIN");
  if (o.trimHull)
    throw usageError(
        "--trim-hull needs the whole TIN; with --block-points the hull's slivers go by "
        "--max-circumradius");
  if (o.snap && *o.snap != 0)
    throw usageError("--block-points merges exact duplicates only: leave out --snap");
  if (o.fullValidation)
    throw usageError("--validate needs the whole TIN in memory",
                     "run `tinsmith validate` on the .tin where it fits");
  if (o.maxCircumradius && !(*o.maxCircumradius > 0))
    throw usageError("--max-circumradius must be a length in metres greater than 0");
  if (!o.crs.empty()) ingest::checkProjectCrs(o.crs, "--crs");
  checkOutputDirectory(o.output, "the TIN (-o)");
  if (!o.report.empty()) checkOutputDirectory(o.report, "the report (--report)");
  ingest::BlockTinOptions options;
  options.crs = o.crs;
  options.blockPoints = *o.blockPoints;
  options.maxCircumradius = o.maxCircumradius.value_or(0.0);
  options.threads = o.threads;
  auto bar = terminalProgress(o.quiet);
  const auto report = ingest::buildTinByBlocks(ingest::pointSources(o.points, o.threads), o.output,
                                               options, bar.get());
  bar.bar.reset();
  finishBlockRun(o, report);
}

// --blocks DIR: a stage of a TIN built by blocks on a cluster (tinsmith
// slurm-tin prepared DIR): one block's triangles (--block K), or the .tin.
void runBlockStage(const TinOptions& o) {
  if (!o.config.empty() || !o.points.empty() || !o.breaklines.empty() || o.blockPoints ||
      o.maxCircumradius || o.trimHull || o.snap || o.fullValidation || !o.crs.empty())
    throw usageError(
        "--blocks runs a stage of points already prepared in blocks: nothing else goes with it",
        "prepare them with tinsmith slurm-tin");
  if (o.blockTask) {
    if (!o.output.empty())
      throw usageError("--block K writes its triangles into --blocks DIR: leave out -o");
    const std::size_t tasks = ingest::blockTasks(o.blocksDir);
    const auto result = ingest::triangulateBlock(o.blocksDir, *o.blockTask, o.threads);
    if (o.quiet) return;
    const ProcessCost cost = processCost();
    std::fprintf(stderr,
                 "block task %zu of %zu: %zu points triangulated (its own and those within reach), "
                 "%zu triangles kept, %zu over the circumradius left out\n"
                 "  process: CPU %.2f s, peak memory %.0f MB\n",
                 *o.blockTask, tasks, result.triangulated, result.kept, result.leftOut,
                 cost.cpuSeconds, cost.peakMegabytes);
    return;
  }
  if (o.output.empty())
    throw usageError("give -o OUT.tin to assemble the blocks, or --block K to triangulate one");
  checkOutputDirectory(o.output, "the TIN (-o)");
  if (!o.report.empty()) checkOutputDirectory(o.report, "the report (--report)");
  auto bar = terminalProgress(o.quiet);
  const auto report = ingest::assembleBlocks(o.blocksDir, o.output, bar.get());
  bar.bar.reset();
  finishBlockRun(o, report);
}

void run(const TinOptions& o) {
  if (!o.blocksDir.empty()) return runBlockStage(o);
  if (o.blockTask) throw usageError("--block K goes with --blocks DIR");
  if (o.output.empty()) throw usageError("give the .tin to write with -o");
  if (o.blockPoints) return runByBlocks(o);
  if (o.maxCircumradius) throw usageError("--max-circumradius goes with --block-points");
  const bool plain = !o.points.empty() || !o.breaklines.empty();
  if (plain && !o.config.empty())
    throw usageError("give either a config file or --points/--breaklines, not both");
  if (!plain && o.config.empty())
    throw usageError("nothing to triangulate",
                     "give a config file (tinsmith tin CONFIG.toml -o OUT.tin) or --points FILE");
  if (plain && o.strict) throw usageError("--strict applies to config runs");
  if (!plain && o.snap) throw usageError("--snap applies to --points/--breaklines runs; set [tin] snap_tolerance in the config");
  if (o.snap && !(*o.snap >= 0)) throw usageError("--snap must be a distance in metres, 0 or more");
  if (o.trimHull && !(*o.trimHull > 0))
    throw usageError("--trim-hull must be a length in metres greater than 0");
  // The TIN's x, y and z are metres: a CRS in feet would put 1000 ft at 1000 m.
  if (plain && !o.crs.empty()) ingest::checkProjectCrs(o.crs, "--crs");
  checkOutputDirectory(o.output, "the TIN (-o)");
  if (!o.report.empty()) checkOutputDirectory(o.report, "the report (--report)");

  auto bar = terminalProgress(o.quiet);
  const ingest::Progress* p = bar.get();

  // The TIN is written straight from the triangulation's mesh, before the
  // triangulation is freed: no TinData copy of it is ever made.
  // With --trim-hull the mesh is copied once, trimmed and written.
  std::size_t trimmed = 0;
  auto writeTin = [&o, &trimmed](const Mesh& mesh) {
    if (!o.trimHull) return ingest::writeTinFile(o.output, mesh, o.threads);
    TinData tin = mesh.toTinData();
    trimmed = trimHull(tin, *o.trimHull);
    ingest::writeTinFile(o.output, tin, o.threads);
  };
  // The options both modes take from the command line.
  auto withFlags = [&o](ingest::BuildOptions options) {
    if (o.fullValidation) options.validation = ingest::BuildValidation::Full;
    options.threads = o.threads;
    return options;
  };
  ingest::BuildReport report;
  if (plain) {
    ingest::BuildOptions options;
    options.crs = o.crs;
    options.snapTolerance = o.snap.value_or(0.0);
    options.flatTriangleRepair = false;
    options.riverDescent = false;
    std::vector<ingest::BuildReport::StageTime> readTimes;
    auto layers = plainLayers(o, readTimes);
    report = ingest::buildTinInto(std::move(layers), withFlags(options), writeTin, p);
    report.times.insert(report.times.begin(), readTimes.begin(), readTimes.end());
    for (const auto& t : readTimes) report.totalSeconds += t.seconds;
  } else {
    ingest::ProjectConfig config = ingest::loadProjectConfig(o.config);
    if (o.strict) config.tin.strict = true;
    if (o.noFlatRepair) config.tin.flatTriangleRepair = false;
    report = ingest::buildTinFromConfig(config, withFlags(ingest::buildOptionsFrom(config)),
                                        writeTin, p);
  }
  bar.bar.reset();
  if (!o.report.empty()) {
    try {
      writeReport(o.report, report);
    } catch (...) {
      std::error_code ec;
      std::filesystem::remove(o.output, ec);  // both outputs or neither
      throw;
    }
  }
  if (!o.quiet) {
    std::cerr << report.summary();
    if (o.trimHull) std::cerr << "  hull trimmed: " << trimmed << " triangles removed\n";
    std::cerr << "wrote " << o.output << "\n";
  }
}

}  // namespace

void addTinCommand(CLI::App& app) {
  auto opt = std::make_shared<TinOptions>();
  auto* cmd = app.add_subcommand("tin", "Build a constrained Delaunay TIN from points and break lines");
  cmd->add_option("config", opt->config, "Project config (TOML); or give --points/--breaklines");
  cmd->add_option("--points", opt->points,
                  "XYZ/CSV point file(s) (plain mode), DEM rasters (.tif .vrt .img .asc .hgt "
                  ".exr …: every valid cell a point at its centre), 3D point layers (OGR), or "
                  "generated points: "
                  "'synthetic:grid?nx=..&ny=..&spacing=..&surface=plane|flat|franke|hill|cone', "
                  "'synthetic:random?n=..&seed=..', 'synthetic:raster?…' (see config/README.md)");
  cmd->add_option("--breaklines", opt->breaklines,
                  "Break lines (plain mode): GeoJSON (Multi)LineString with 3D coordinates, text "
                  "polylines (.txt/.xyz: x y z per line, a blank line between polylines), or "
                  "generated lines: 'synthetic:lines?n=..&layout=hatch|cross|star|random', "
                  "'synthetic:rings?n=..&interval=..'");
  addOutputOption(*cmd, opt->output,
                  "The .tin file to write (required but with --blocks DIR --block K)");
  cmd->add_option("--report", opt->report, "Also write the build report as JSON to this file");
  cmd->add_option("--snap", opt->snap, "Plain mode: merge points closer than this (metres; default 0)");
  addCrsOption(*cmd, opt->crs, "Plain mode: the CRS to record in the TIN");
  cmd->add_flag("--strict", opt->strict, "Config mode: crossing contours are fatal, not just reported");
  cmd->add_flag("--no-flat-repair", opt->noFlatRepair, "Config mode: keep flat triangles");
  cmd->add_option("--trim-hull", opt->trimHull,
                  "Remove the convex hull's slivers around non-convex data (a projected DEM's "
                  "curved edges): hull triangles whose outer edge is longer than this many "
                  "metres, from the outside in (e.g. 3 × the grid spacing)");
  cmd->add_option("--block-points", opt->blockPoints,
                  "Build the TIN block by block, each block holding about this many points, "
                  "for more points than memory holds (plain mode, --points only): the points "
                  "go through files next to the output, one block in memory at a time")
      ->check(CLI::Range(std::size_t{16}, std::numeric_limits<std::size_t>::max()));
  cmd->add_option("--max-circumradius", opt->maxCircumradius,
                  "With --block-points: leave out the Delaunay triangles whose circumcircle's "
                  "radius is more than this many metres (the hull's slivers and gaps in the data "
                  "wider than twice it); each block reads the points within twice it. Default: "
                  "8 × the points' mean spacing");
  cmd->add_option("--blocks", opt->blocksDir,
                  "A folder of points prepared in blocks by tinsmith slurm-tin: with --block K "
                  "triangulate its block task K, else assemble the .tin (-o) from every task's "
                  "triangles (what its Slurm jobs run)");
  cmd->add_option("--block", opt->blockTask, "With --blocks: the block task to triangulate (0 …)");
  cmd->add_flag("--validate", opt->fullValidation,
                "Run the full validator on the result (Delaunay property, every input point and "
                "constraint present); by default only the mesh's structure is checked");
  addThreadsOption(*cmd, opt->threads, "Threads for reading XYZ/CSV points, the triangulation, its check and the .tin checksum", "the TIN is the same for any count");
  addQuietFlag(*cmd, opt->quiet, "No summary and no progress on stderr");
  cmd->callback([opt] { run(*opt); });
}

}  // namespace tinsmith::cli
