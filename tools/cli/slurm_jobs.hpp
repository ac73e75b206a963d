// What the commands that write and submit Slurm jobs share (tinsmith slurm,
// tinsmith slurm-tin): quoting for the scripts, atomic script files, sbatch
// runs, array lists; and what a process cost, for the lines the jobs' logs
// end with.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace tinsmith::cli {

/// `text` quoted for a POSIX shell.
std::string shellQuote(const std::string& text);
/// Writes `text` to `path` through a temporary sibling and a rename.
void writeAtomically(const std::filesystem::path& path, const std::string& text, bool executable);
/// Runs `command` (/bin/sh) and returns its stdout up to a ';' (sbatch
/// --parsable's "ID;CLUSTER"); throws ioError naming it and what it printed
/// on a non-zero exit.
std::string runForOutput(const std::string& command);
/// "0-16" or "3,5,9": sbatch --array's list.
std::string arrayList(const std::vector<int>& tasks);
/// "afterok:A_3:A_5…": every listed task of array job `arrayId`.
std::string afterEveryTask(const std::string& arrayId, const std::vector<int>& tasks);

/// This process's CPU time (user + system) and peak memory so far.
struct ProcessCost {
  double cpuSeconds = 0;
  double peakMegabytes = 0;
};
ProcessCost processCost();

}  // namespace tinsmith::cli
