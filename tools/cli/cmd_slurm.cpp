// `tinsmith slurm`: one tiling job as Slurm batch jobs on a shared filesystem,
// no tinsmith daemon:
//   tinsmith slurm SITE.tin -o SITE.3dtiles --shard-zoom Z --workdir DIR [tile options]
//       [--submit] [--resume] [--sbatch-args 'ARGS'] [--json]
// writes into DIR
//   plan.json   what the job is (TIN, output, options, shard zoom) and every
//               submission made of it;
//   shard.sh    an sbatch array script: task 0 reads the whole TIN once,
//               plans the pyramid (the planning fit, which chooses the
//               finest zoom; the lines simplified for each zoom) into
//               tiler.plan (ingest/tiles/tiling_plan.hpp) and tiles the top
//               of the pyramid (tinsmith tile --until-zoom Z --write-plan)
//               — over 2^18 vertices only from the mosaic zoom K down, as
//               every shard leaves the tiles above K to the merge;
//               task k ≥ 1 the subtree Z/x/y with k − 1 = y · 2^Z + x, given
//               the plan (--plan: it reads only its square of the TIN) and
//               --subtree --unchecked-ancestors (a subtree under a tile that
//               does not refine, or without terrain, is written all the
//               same, and the merge leaves it out); shards/k.3dtiles,
//               logs/shard-k.log;
//   merge.sh    tinsmith merge of every shard into the output (building
//               the tiles above K from the surfaces of the shards' zoom-K
//               tiles, with the shards' cores), then info,
//               then what each shard cost, from the "process:" line of
//               tinsmith tile's summary in its log (logs/merge.log);
// and with --submit runs `sbatch --array=0` (the top), `sbatch --array` of
// the subtrees after it and `sbatch` of the merge after every task (afterok).
// Nothing heavy runs where tinsmith slurm runs (a login node): it reads the
// TIN's header, CRS and index summary only (the vertex count bounds the
// mosaic zoom), and with --resume the shards' stores (each
// tile's bytes against its CRC-32: the output's size, read once).
// --resume resubmits only the tasks that left no finished
// store (a failed, cancelled, lost or damaged shard, or one holding a tile
// whose bytes changed; the top too when tiler.plan is gone
// and a subtree still needs it),
// and a new merge after them, and refuses while the last submission's jobs
// are queued or running (plan.json records their ids, also of a submission
// that failed half way). Shards are built exactly as `tinsmith tile
// --subtree` builds them, so the merged store has the bytes of one run.
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/tiles/tiler.hpp"
#include "ingest/tiles/proj_georeference.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/slurm_jobs.hpp"
#include "tools/cli/tile_options.hpp"

namespace tinsmith::cli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kPlanFormat = "tinsmith-slurm/2";  // 2: the top task plans
constexpr int kMaxShardZoom = 6;  // 4096 subtrees: as many as an array usually may hold

struct SlurmCliOptions {
  std::string tin, output, workdir, sbatchArgs;
  int shardZoom = 0;
  TileFlags flags;
  bool submit = false;
};

/// The tile options every shard is run with, as `tinsmith tile` arguments
/// (what the shards' stores record, so the merge sees one job).
std::vector<std::string> tileArguments(const TileFlags& f) {
  std::vector<std::string> a;
  const auto num = [](double v) {  // the shortest text that reads back as v
    char buffer[32];
    const auto end = std::to_chars(buffer, buffer + sizeof buffer, v).ptr;
    return std::string(buffer, end);
  };
  if (f.tolerance) a.insert(a.end(), {"--tolerance", num(*f.tolerance)});
  if (f.maxTriangles) a.insert(a.end(), {"--max-triangles", std::to_string(*f.maxTriangles)});
  if (f.maxZoom) a.insert(a.end(), {"--max-zoom", std::to_string(*f.maxZoom)});
  if (f.lambda) a.insert(a.end(), {"--lambda", num(*f.lambda)});
  if (f.compression) a.insert(a.end(), {"--compression", *f.compression});
  if (f.frame) a.insert(a.end(), {"--frame", *f.frame});
  if (f.geoid) a.insert(a.end(), {"--geoid", *f.geoid});
  return a;
}

std::string shardScript(const std::string& tinsmith, const fs::path& tin, const fs::path& dir,
                        const std::vector<std::string>& args, int shardZoom, int cpus) {
  const std::string plan = shellQuote((dir / "tiler.plan").string());
  std::string quoted;
  for (const auto& a : args) quoted += " " + shellQuote(a);
  std::ostringstream s;
  s << "#!/usr/bin/env bash\n"
    << "# One shard of a tinsmith tiling job (written by tinsmith slurm; see plan.json).\n"
    << "# Task 0: the job's plan (tiler.plan) and the tiles above zoom " << shardZoom
    << "; task k >= 1, after it: the subtree " << shardZoom << "/x/y, k - 1 = y * "
    << (1 << shardZoom) << " + x.\n"
    << "#SBATCH --job-name=tinsmith-shard\n"
    << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "# Its log: logs/shard-TASK.log (sbatch --output, on the command line).\n"
    << "set -euo pipefail\n"
    << "task=${SLURM_ARRAY_TASK_ID:?run by sbatch --array}\n"
    << "shards=" << shellQuote((dir / "shards").string()) << "\n"
    << "tile=(" << shellQuote(tinsmith) << " tile " << shellQuote(tin.string()) << quoted
    << " --threads \"${SLURM_CPUS_PER_TASK:-1}\")\n"
    << "echo \"tinsmith shard $task on $(hostname) at $(date -u +%FT%TZ)\"\n"
    << "if [ \"$task\" -eq 0 ]; then\n"
    << "  \"${tile[@]}\" --until-zoom " << shardZoom << " --write-plan " << plan
    << " -o \"$shards/0.3dtiles\"\n"
    << "  exit 0\n"
    << "fi\n"
    << "n=" << (1 << shardZoom) << "\n"
    << "x=$(( (task - 1) % n )); y=$(( (task - 1) / n ))\n"
    << "\"${tile[@]}\" --plan " << plan << " --subtree \"" << shardZoom
    << "/$x/$y\" --unchecked-ancestors -o \"$shards/$task.3dtiles\"\n";
  return s.str();
}

std::string mergeScript(const std::string& tinsmith, const fs::path& dir, const fs::path& output,
                        int tasks, bool strict, int cpus) {
  std::ostringstream s;
  s << "#!/usr/bin/env bash\n"
    << "# The merge of a tinsmith tiling job's shards (written by tinsmith slurm): over\n"
    << "# 2^18 TIN vertices it also builds the tiles above the mosaic zoom, from the\n"
    << "# shards' zoom-K tiles.\n"
    << "#SBATCH --job-name=tinsmith-merge\n"
    << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "# Its log: logs/merge.log (sbatch --output, on the command line).\n"
    << "set -euo pipefail\n"
    << "shards=" << shellQuote((dir / "shards").string()) << "\n"
    << "stores=()\n"
    << "for task in $(seq 0 " << tasks - 1 << "); do\n"
    << "  if [ ! -e \"$shards/$task.3dtiles\" ]; then\n"
    << "    echo \"ERROR: shard $task has no store: run tinsmith slurm --resume --submit "
       "with the same arguments\" >&2\n"
    << "    exit 3\n"
    << "  fi\n"
    << "  stores+=(\"$shards/$task.3dtiles\")\n"
    << "done\n"
    // With --strict the merge's exit code 1 (a tile over its zoom's
    // tolerance) is the job's, after the store, info and the costs.
    << "merged=0\n"
    << shellQuote(tinsmith) << " merge \"${stores[@]}\" -o " << shellQuote(output.string())
    << " --threads \"${SLURM_CPUS_PER_TASK:-1}\"" << (strict ? " --strict" : "")
    << " || merged=$?\n"
    << "if [ \"$merged\" -ne 0 ] && [ \"$merged\" -ne 1 ]; then exit \"$merged\"; fi\n"
    << shellQuote(tinsmith) << " info " << shellQuote(output.string())
    << "\n"
    // What each shard cost, from tinsmith tile's "process:" line in its log.
    << taskCostLines(dir / "logs", "shard", "shard", static_cast<std::size_t>(tasks))
    << "exit \"$merged\"\n";
  return s.str();
}

/// The tasks that have left no finished store (ingest::isFinishedShard: a
/// store that is missing, damaged or lost tiles is built again, and with
/// `checkTileBytes` one holding a tile whose bytes are not those its shard
/// finished with), and the
/// top when a subtree among them needs the plan the top writes and it is
/// gone (the merge does not read it: with every store there, nothing is
/// rerun for it).
std::vector<int> unfinishedTasks(const fs::path& dir, int tasks, bool checkTileBytes) {
  std::vector<int> out;
  for (int k = 0; k < tasks; ++k)
    if (!ingest::isFinishedShard(dir / "shards" / (std::to_string(k) + ".3dtiles"), checkTileBytes))
      out.push_back(k);
  if (!out.empty() && out.front() != 0 && !fs::exists(dir / "tiler.plan"))
    out.insert(out.begin(), 0);
  return out;
}

void runSlurm(const SlurmCliOptions& o) {
  const TileFlags& f = o.flags;
  if (o.shardZoom < 1 || o.shardZoom > kMaxShardZoom)
    throw usageError("--shard-zoom must be 1 to " + std::to_string(kMaxShardZoom) + " (got " +
                         std::to_string(o.shardZoom) + ")",
                     "zoom Z gives 4^Z subtrees and the top above them");
  if (f.scheme && *f.scheme != "3d-tiles")
    throw usageError("Cesium terrain (--scheme " + *f.scheme + ") is built whole, not in shards",
                     "tile it with tinsmith tile, and shard the 3D Tiles here");
  if (f.resume && !o.submit) throw usageError("--resume goes with --submit");
  // The options every shard will run with, checked here once.
  (void)withTileFlags(ingest::TileJobOptions{}, f);
  const fs::path tin = fs::absolute(o.tin).lexically_normal();
  if (!fs::is_regular_file(tin))
    throw inputError("no TIN at '" + o.tin + "'", fileLocation(o.tin), "give a .tin file");
  const fs::path output = fs::absolute(o.output).lexically_normal();
  const fs::path dir = fs::absolute(o.workdir).lexically_normal();
  const std::string tinsmith = fs::canonical("/proc/self/exe").string();
  const int tasks = 1 + (1 << (2 * o.shardZoom));
  std::vector<std::string> args = tileArguments(f);

  nlohmann::ordered_json plan;
  plan["format"] = kPlanFormat;
  plan["tin"] = tin.string();
  plan["output"] = output.string();
  plan["shardZoom"] = o.shardZoom;
  plan["tasks"] = tasks;
  plan["tileArguments"] = args;
  const fs::path planPath = dir / "plan.json";
  nlohmann::ordered_json previous;
  if (fs::exists(planPath)) {
    std::ifstream in(planPath);
    previous = nlohmann::ordered_json::parse(in, nullptr, false);
    nlohmann::ordered_json same = previous;
    if (same.is_object()) same.erase("submissions");
    if (same != plan)
      throw usageError("'" + dir.string() + "' holds the plan of another job (plan.json)",
                       "choose another --workdir, or give the arguments that job was planned with");
    if (!f.resume && unfinishedTasks(dir, tasks, false).size() < static_cast<std::size_t>(tasks))
      throw usageError("'" + dir.string() + "' already holds shards of this job",
                       "add --resume to submit only the shards that are missing (or the merge "
                       "alone, when none is)");
  } else if (fs::exists(dir) && !fs::is_empty(dir)) {
    throw usageError("'" + dir.string() + "' is a folder that holds other files",
                     "give an empty or new --workdir: tinsmith slurm keeps its plan, scripts, "
                     "shards and logs there");
  }
  // The shards and the plan name the TIN by the CRC of its bytes in this
  // format, which a subtree shard takes from the file's header.
  ingest::requireTinCrs(ingest::requireCurrentTinFormat(tin).crs, tin.string());
  // A shard zoom above the mosaic zoom would fail task 0: refused here from
  // the vertex count alone (the header and the index's summary). The mosaic
  // zoom is at most this bound (also at most the planned finest zoom).
  const tiles::Rect nowhere{1e300, 1e300, 1e300, 1e300};
  const std::size_t vertices = ingest::readTinFilePart(tin, nowhere, nowhere).vertices;
  if (const int k = tiles::mosaicZoomFor(vertices, tiles::TilerOptions{}.mosaicPoints, 30);
      o.shardZoom < k)
    throw usageError("--shard-zoom " + std::to_string(o.shardZoom) +
                         " may lie above the mosaic zoom of a TIN of " + std::to_string(vertices) +
                         " vertices (" + std::to_string(k) +
                         ", unless its planned finest zoom is less): the tiles above that zoom "
                         "are fitted to the mosaic of all of its tiles, built only as the whole "
                         "top, and task 0 would refuse the shards",
                     "give --shard-zoom " + std::to_string(k) + " or more");
  makeFolder(dir / "shards");
  makeFolder(dir / "logs");
  const int cpus = std::max(1, f.threads);
  writeAtomically(dir / "shard.sh", shardScript(tinsmith, tin, dir, args, o.shardZoom, cpus), true);
  writeAtomically(dir / "merge.sh", mergeScript(tinsmith, dir, output, tasks, f.strict, cpus),
                  true);

  std::vector<int> todo;
  if (f.resume) {
    refuseWhileQueued(previous);
    todo = unfinishedTasks(dir, tasks, true);
  } else {
    for (int k = 0; k < tasks; ++k) todo.push_back(k);
  }
  // The top (task 0) writes the plan the subtrees read: they wait for it.
  ArrayThenJob jobs;
  jobs.arrayScript = dir / "shard.sh";
  jobs.afterScript = dir / "merge.sh";
  jobs.arrayLog = dir / "logs" / "shard-%a.log";
  jobs.afterLog = dir / "logs" / "merge.log";
  jobs.sbatchArgs = o.sbatchArgs;
  for (const int k : todo) (k == 0 ? jobs.headTasks : jobs.tasks).push_back(k);
  if (previous.is_object() && previous.contains("submissions"))
    plan["submissions"] = previous["submissions"];
  const auto submission = submitAndRecord(jobs, plan, planPath, "merge", o.submit);

  if (f.json) {
    nlohmann::ordered_json out = submission;
    out["workdir"] = dir.string();
    if (!o.submit) out["commands"] = jobs.shellLines();
    std::cout << out.dump(2) << "\n";
    return;
  }
  if (f.quiet) return;
  std::cerr << "wrote " << (dir / "shard.sh").string() << " (" << tasks
            << " tasks: the plan and the top above zoom " << o.shardZoom << ", then " << tasks - 1
            << " subtrees) and merge.sh; logs in " << (dir / "logs").string() << "\n";
  if (!o.submit) {
    // The commands on stdout, to be saved and run: `tinsmith slurm … > submit.sh`.
    for (const auto& line : jobs.shellLines()) std::cout << line << "\n";
    std::cerr << "submit with the commands above (or run tinsmith slurm again with --submit)\n";
    return;
  }
  if (todo.empty()) {
    std::cerr << "every shard is there: submitted the merge alone, job " << jobs.afterId << "\n";
    return;
  }
  if (!jobs.headId.empty())
    std::cerr << "submitted the plan and the top as job " << jobs.headId
              << (jobs.tasks.empty() ? "" : ", the subtrees after it");
  else
    std::cerr << "submitted the subtrees";
  if (!jobs.tasks.empty())
    std::cerr << " as array job " << jobs.arrayId << " (tasks " << arrayList(jobs.tasks) << ")";
  std::cerr << ", and the merge as job " << jobs.afterId << " after every one of them\n"
            << "follow with: squeue; the merged store is " << output.string()
            << "; a failed shard: tinsmith slurm … --resume --submit\n";
}

}  // namespace

void addSlurmCommand(CLI::App& app) {
  auto opt = std::make_shared<SlurmCliOptions>();
  auto* cmd = app.add_subcommand(
      "slurm", "Tile a TIN as Slurm jobs: an sbatch array of shards and a merge after them");
  cmd->add_option("tin", opt->tin, "The .tin file to tile (on a filesystem the nodes share)")
      ->required();
  addOutputOption(*cmd, opt->output, "The merged tile store (.3dtiles or a directory)")->required();
  cmd->add_option("--shard-zoom", opt->shardZoom,
                  "The subtrees' zoom: 4^Z subtrees, and the tiles above them as one more task")
      ->required();
  cmd->add_option("--workdir", opt->workdir,
                  "Where the plan, the scripts, the shards and the logs go (shared by the nodes)")
      ->required();
  cmd->add_flag("--submit", opt->submit, "Submit the jobs with sbatch (else print the commands)");
  cmd->add_option("--sbatch-args", opt->sbatchArgs,
                  "More sbatch arguments for both jobs, as one string (e.g. '-p big -A proj')");
  addTileFlags(*cmd, opt->flags, false);
  cmd->get_option("--resume")
      ->description(
          "With --submit: submit only the shards that left no store (failed, cancelled or lost) "
          "and a merge after them");
  cmd->get_option("--strict")
      ->description(
          "The merge job ends with exit code 1 (the merged store is still written) when a tile's "
          "measured error is over its zoom's tolerance (the shards do not fail for it)");
  cmd->get_option("--threads")
      ->description("Cores each shard asks Slurm for (--cpus-per-task) and runs on (default 1)");
  cmd->callback([opt] { runSlurm(*opt); });
}

}  // namespace tinsmith::cli
