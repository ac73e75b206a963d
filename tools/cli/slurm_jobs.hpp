// What the commands that write and submit Slurm jobs share (tinsmith slurm,
// tinsmith slurm-tin): quoting for the scripts, atomic script files, sbatch
// runs, array lists; and what a process cost, for the lines the jobs' logs
// end with.
#pragma once

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tinsmith::cli {

/// `text` quoted for a POSIX shell.
std::string shellQuote(const std::string& text);
/// Writes `text` to `path` through a temporary sibling and a rename.
void writeAtomically(const std::filesystem::path& path, const std::string& text, bool executable);
/// Creates `folder` and its parents; throws ioError naming it when it cannot.
void makeFolder(const std::filesystem::path& folder);
/// Runs `command` (/bin/sh) and returns its stdout up to a ';' (sbatch
/// --parsable's "ID;CLUSTER"); throws ioError naming it and what it printed
/// on a non-zero exit.
std::string runForOutput(const std::string& command);
/// The cluster's MaxArraySize (scontrol show config), or 0 when unknown.
int maxArraySize();
/// Those of `ids` that squeue still lists (pending or running, or a task of
/// such an array); none when squeue cannot be run.
std::vector<std::string> queuedJobs(const std::vector<std::string>& ids);
/// "0-16" or "3,5,9": sbatch --array's list.
std::string arrayList(const std::vector<int>& tasks);
/// "afterok:A_3:A_5…": every listed task of array job `arrayId`.
std::string afterEveryTask(const std::string& arrayId, const std::vector<int>& tasks);

/// Bash lines that print, for tasks 0 … tasks − 1, what each cost — from the
/// last "  process: CPU …" line of its log LOGS/PREFIX-TASK.log — as
/// "  LABEL TASK: CPU S s, peak memory M MB", then "  all: …".
std::string taskCostLines(const std::filesystem::path& logs, const std::string& prefix,
                          const std::string& label, std::size_t tasks);

/// An sbatch array of `tasks` and a job after every one of them (afterok;
/// none with no task): the commands, and the job ids once submitted. With
/// `headTasks`, those tasks of the same script run first, as an array of
/// their own, and `tasks` and the job after wait for every one of them too
/// (a task that makes what the others read).
struct ArrayThenJob {
  std::vector<int> tasks;
  std::filesystem::path arrayScript, afterScript;
  /// Their logs (sbatch --output; %a is the task).
  std::filesystem::path arrayLog, afterLog;
  std::string sbatchArgs;  ///< more arguments for every job, as one string
  std::vector<int> headTasks;
  std::string headId, arrayId, afterId;

  /// The head array (none without head tasks: "").
  [[nodiscard]] std::string headCommand() const;
  /// The array after the head array whose id is `head` (a shell variable or
  /// a placeholder, for the printed commands; unused without head tasks).
  [[nodiscard]] std::string arrayCommand(const std::string& head = {}) const;
  /// The job after the array whose id is `id` and the head array `head`.
  [[nodiscard]] std::string afterCommand(const std::string& id, const std::string& head = {}) const;
  /// The commands to run in order, as shell lines that keep each id in a
  /// variable (H, A) for the next.
  [[nodiscard]] std::vector<std::string> shellLines() const;
  /// Runs them with sbatch --parsable, the ids kept as each is queued.
  /// Throws usageError, submitting nothing, when the cluster's MaxArraySize
  /// is too small for the tasks; ioError as runForOutput, naming the jobs
  /// already queued.
  void submit();
};

/// A job folder's plan.json: what the job is, and its "submissions", each
/// {"tasks": [the array's tasks], and the ids queued: "top" (head tasks),
/// "array" and the job after them under its own key}.
///
/// Throws usageError while a job of the last submission in `plan` is still
/// queued or running (squeue): a task resubmitted would run twice, the
/// second taking the first's stage from under it.
void refuseWhileQueued(const nlohmann::ordered_json& plan);
/// Writes `plan` to `planPath` (its earlier submissions kept); with `submit`,
/// before anything is submitted, then submits `jobs` and writes it again
/// with this submission appended — also when sbatch fails half way (the
/// error rethrown), so the folder stays this job's and --resume takes it.
/// The job after the array is recorded under `afterKey`. Returns the
/// submission (its tasks, and the ids when submitted).
nlohmann::ordered_json submitAndRecord(ArrayThenJob& jobs, nlohmann::ordered_json plan,
                                       const std::filesystem::path& planPath,
                                       const std::string& afterKey, bool submit);

/// This process's CPU time (user + system) and peak memory so far.
struct ProcessCost {
  double cpuSeconds = 0;
  double peakMegabytes = 0;
};
ProcessCost processCost();

}  // namespace tinsmith::cli
