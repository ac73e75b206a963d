// `tinsmith slurm-tin`: a TIN of more points than one machine holds, built
// block by block as Slurm batch jobs on a shared filesystem, no daemon:
//   tinsmith slurm-tin --points FILE... -o SITE.tin --block-points N --workdir DIR
//       [--max-circumradius R] [--crs C] [--threads T] [--submit] [--resume]
//       [--sbatch-args 'ARGS'] [--json]
// prepares the points here (ingest/build/block_tin.hpp stage 1: spooled,
// bucketed into blocks and deduplicated into DIR, one block in memory at a
// time) and writes into DIR
//   plan.json     what the job is (points, output, options) and every
//                 submission made of it;
//   blocks.json   the blocks (stage 1's account);
//   block.sh      an sbatch array script: task k triangulates the k-th block
//                 with points (tinsmith tin --blocks DIR --block k) into
//                 triangles/k.tri; logs/block-k.log;
//   assemble.sh   tinsmith tin --blocks DIR -o SITE.tin, then info, then what
//                 each task cost (logs/assemble.log);
// and with --submit runs `sbatch --array` of the tasks and `sbatch` of the
// assembly with afterok on each task (plan.json records the ids queued, also
// of a submission that failed half way). --resume resubmits only the tasks
// that left no triangles, and the assembly after them, and refuses while
// the last submission's jobs are queued or running. The .tin has the bytes
// `tinsmith tin --block-points N` writes on one machine; tile it on the
// cluster with `tinsmith slurm SITE.tin …`.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "ingest/build/block_tin.hpp"
#include "ingest/config/project_config.hpp"
#include "ingest/readers/point_sources.hpp"
#include "ingest/readers/synthetic_reader.hpp"
#include "tools/cli/commands.hpp"
#include "tools/cli/output_paths.hpp"
#include "tools/cli/progress_bar.hpp"
#include "tools/cli/shared_options.hpp"
#include "tools/cli/slurm_jobs.hpp"

namespace tinsmith::cli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kPlanFormat = "tinsmith-slurm-tin/1";

struct SlurmTinOptions {
  std::vector<std::string> points;
  std::string output, workdir, sbatchArgs, crs;
  std::size_t blockPoints = 0;
  std::optional<double> maxCircumradius;
  unsigned threads = 1;
  bool submit = false, resume = false, json = false, quiet = false;
};

std::string blockScript(const std::string& tinsmith, const fs::path& dir, unsigned cpus) {
  std::ostringstream s;
  s << "#!/usr/bin/env bash\n"
    << "# One block of a TIN built by blocks (written by tinsmith slurm-tin; see plan.json).\n"
    << "#SBATCH --job-name=tinsmith-block\n"
    << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "# Its log: logs/block-TASK.log (sbatch --output, on the command line).\n"
    << "set -euo pipefail\n"
    << "task=${SLURM_ARRAY_TASK_ID:?run by sbatch --array}\n"
    << "echo \"tinsmith block task $task on $(hostname) at $(date -u +%FT%TZ)\"\n"
    << shellQuote(tinsmith) << " tin --blocks " << shellQuote(dir.string())
    << " --block \"$task\" --threads \"${SLURM_CPUS_PER_TASK:-1}\"\n";
  return s.str();
}

std::string assembleScript(const std::string& tinsmith, const fs::path& dir, const fs::path& output,
                           std::size_t tasks) {
  std::ostringstream s;
  s << "#!/usr/bin/env bash\n"
    << "# The assembly of a TIN built by blocks (written by tinsmith slurm-tin).\n"
    << "#SBATCH --job-name=tinsmith-assemble\n"
    << "# Its log: logs/assemble.log (sbatch --output, on the command line).\n"
    << "set -euo pipefail\n"
    << shellQuote(tinsmith) << " tin --blocks " << shellQuote(dir.string()) << " -o "
    << shellQuote(output.string()) << "\n"
    << shellQuote(tinsmith) << " info " << shellQuote(output.string())
    << "\n"
    // What each task cost, from tinsmith tin's "process:" line in its log.
    << taskCostLines(dir / "logs", "block", "task", tasks);
  return s.str();
}

void runSlurmTin(const SlurmTinOptions& o) {
  if (o.resume && !o.submit) throw usageError("--resume goes with --submit");
  if (o.maxCircumradius && !(*o.maxCircumradius > 0))
    throw usageError("--max-circumradius must be a length in metres greater than 0");
  if (o.blockPoints < 16) throw usageError("--block-points must be at least 16");
  if (!o.crs.empty()) ingest::checkProjectCrs(o.crs, "--crs");
  const fs::path output = fs::absolute(o.output).lexically_normal();
  checkOutputDirectory(output.string(), "the TIN (-o)");
  const fs::path dir = fs::absolute(o.workdir).lexically_normal();
  const std::string tinsmith = fs::canonical("/proc/self/exe").string();

  nlohmann::ordered_json plan;
  plan["format"] = kPlanFormat;
  std::vector<std::string> points;
  for (const auto& p : o.points)
    points.push_back(ingest::isSyntheticSpec(p) ? p : fs::absolute(p).lexically_normal().string());
  plan["points"] = points;
  plan["output"] = output.string();
  plan["crs"] = o.crs;
  plan["blockPoints"] = o.blockPoints;
  plan["maxCircumradius"] = o.maxCircumradius.value_or(0.0);
  const fs::path planPath = dir / "plan.json";
  nlohmann::ordered_json previous;
  bool prepared = false;
  if (fs::exists(planPath)) {
    std::ifstream in(planPath);
    previous = nlohmann::ordered_json::parse(in, nullptr, false);
    nlohmann::ordered_json same = previous;
    if (same.is_object()) {
      same.erase("submissions");
      same.erase("tasks");
    }
    if (same != plan)
      throw usageError("'" + dir.string() + "' holds the plan of another job (plan.json)",
                       "choose another --workdir, or give the arguments that job was planned with");
    prepared = previous.contains("tasks") && fs::exists(dir / "blocks.json");
    if (prepared && !o.resume)
      throw usageError("'" + dir.string() + "' already holds this job's blocks",
                       "add --resume --submit to submit only the block tasks that left no "
                       "triangles (or the assembly alone, when none did)");
  } else if (fs::exists(dir) && !fs::is_empty(dir)) {
    throw usageError("'" + dir.string() + "' is a folder that holds other files",
                     "give an empty or new --workdir: tinsmith slurm-tin keeps its points, "
                     "blocks, scripts and logs there");
  }
  if (!prepared) {
    // plan.json first, without the tasks: a preparation cut short leaves a
    // folder that this job's rerun prepares again.
    makeFolder(dir);
    for (const auto* sub : {"points", "triangles"}) fs::remove_all(dir / sub);
    fs::remove(dir / "blocks.json");
    writeAtomically(planPath, plan.dump(2) + "\n", false);
    ingest::BlockTinOptions options;
    options.crs = o.crs;
    options.blockPoints = o.blockPoints;
    options.maxCircumradius = o.maxCircumradius.value_or(0.0);
    auto bar = terminalProgress(o.quiet || o.json);
    const auto report =
        ingest::prepareBlocks(ingest::pointSources(o.points, 1), dir, options, bar.get());
    bar.bar.reset();
    if (!o.quiet && !o.json)
      std::cerr << "prepared " << report.inputPoints << " points (" << report.duplicates
                << " exact duplicates dropped) in " << report.blocks << " blocks of "
                << report.blockSide << " m, each to be triangulated with the points within "
                << 2 * report.maxCircumradius << " m of it\n";
  }
  const std::size_t tasks = ingest::blockTasks(dir);
  plan["tasks"] = tasks;
  makeFolder(dir / "logs");
  const unsigned cpus = std::max(1u, o.threads);
  writeAtomically(dir / "block.sh", blockScript(tinsmith, dir, cpus), true);
  writeAtomically(dir / "assemble.sh", assembleScript(tinsmith, dir, output, tasks), true);

  std::vector<int> todo;
  if (o.resume) {
    refuseWhileQueued(previous);
    for (const std::size_t k : ingest::untriangulatedBlocks(dir))
      todo.push_back(static_cast<int>(k));
  } else {
    for (std::size_t k = 0; k < tasks; ++k) todo.push_back(static_cast<int>(k));
  }
  ArrayThenJob jobs;
  jobs.tasks = todo;
  jobs.arrayScript = dir / "block.sh";
  jobs.afterScript = dir / "assemble.sh";
  jobs.arrayLog = dir / "logs" / "block-%a.log";
  jobs.afterLog = dir / "logs" / "assemble.log";
  jobs.sbatchArgs = o.sbatchArgs;
  if (previous.is_object() && previous.contains("submissions"))
    plan["submissions"] = previous["submissions"];
  const auto submission = submitAndRecord(jobs, plan, planPath, "assemble", o.submit);

  if (o.json) {
    nlohmann::ordered_json out = submission;
    out["workdir"] = dir.string();
    out["blockTasks"] = tasks;
    if (!o.submit) out["commands"] = jobs.shellLines();
    std::cout << out.dump(2) << "\n";
    return;
  }
  if (o.quiet) return;
  std::cerr << "wrote " << (dir / "block.sh").string() << " (" << tasks
            << " block tasks) and assemble.sh; logs in " << (dir / "logs").string() << "\n";
  if (!o.submit) {
    for (const auto& line : jobs.shellLines()) std::cout << line << "\n";
    std::cerr << "submit with the two commands above (or run tinsmith slurm-tin again with "
                 "--resume --submit)\n";
    return;
  }
  if (todo.empty())
    std::cerr << "every block task is done: submitted the assembly alone, job " << jobs.afterId
              << "\n";
  else
    std::cerr << "submitted the block tasks as array job " << jobs.arrayId << " (tasks "
              << arrayList(todo) << ") and the assembly as job " << jobs.afterId
              << " after every one of them\n"
              << "follow with: squeue; the TIN is " << output.string()
              << "; a failed task: tinsmith slurm-tin … --resume --submit\n";
}

}  // namespace

void addSlurmTinCommand(CLI::App& app) {
  auto opt = std::make_shared<SlurmTinOptions>();
  auto* cmd = app.add_subcommand(
      "slurm-tin",
      "Build a TIN of more points than one machine holds as Slurm jobs: the points prepared in "
      "blocks here, an sbatch array of block tasks and an assembly after them");
  cmd->add_option("--points", opt->points,
                  "XYZ/CSV point files (read a chunk at a time), DEM rasters (read in strips) or "
                  "3D point layers")
      ->required();
  addOutputOption(*cmd, opt->output, "The .tin file to write (on a filesystem the nodes share)")
      ->required();
  cmd->add_option("--block-points", opt->blockPoints,
                  "About this many points a block (a task holds its block and the points within "
                  "twice --max-circumradius of it)")
      ->required();
  cmd->add_option("--max-circumradius", opt->maxCircumradius,
                  "Leave out the Delaunay triangles whose circumcircle's radius is more than this "
                  "many metres (default: 8 × the points' mean spacing)");
  addCrsOption(*cmd, opt->crs, "The CRS to record in the TIN");
  cmd->add_option("--workdir", opt->workdir,
                  "Where the blocks, the scripts and the logs go (shared by the nodes)")
      ->required();
  cmd->add_flag("--submit", opt->submit, "Submit the jobs with sbatch (else print the commands)");
  cmd->add_flag("--resume", opt->resume,
                "With --submit: submit only the block tasks that left no triangles, and the "
                "assembly after them");
  cmd->add_option("--sbatch-args", opt->sbatchArgs,
                  "More sbatch arguments for both jobs, as one string (e.g. '-p big -A proj')");
  cmd->add_option("--threads", opt->threads,
                  "Cores each block task asks Slurm for (--cpus-per-task) and runs on (default 1)");
  cmd->add_flag("--json", opt->json, "Print what was written and submitted as JSON on stdout");
  addQuietFlag(*cmd, opt->quiet, "No summary and no progress on stderr");
  cmd->callback([opt] { runSlurmTin(*opt); });
}

}  // namespace tinsmith::cli
