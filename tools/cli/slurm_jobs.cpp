#include "tools/cli/slurm_jobs.hpp"

#include <sys/resource.h>

#include <cstdio>
#include <fstream>
#include <utility>

#include "core/base/error.hpp"

namespace tinsmith::cli {

namespace fs = std::filesystem;

std::string shellQuote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

void writeAtomically(const fs::path& path, const std::string& text, bool executable) {
  const fs::path temp = path.string() + ".tmp";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out)
      throw ioError("cannot write '" + temp.string() + "'", fileLocation(temp.string()),
                    "check that the work folder is writable and has room");
  }
  if (executable)
    fs::permissions(temp, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                    fs::perm_options::add);
  fs::rename(temp, path);
}

std::string runForOutput(const std::string& command) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) throw ioError("cannot run: " + command, {}, "check that sbatch is on PATH");
  std::string out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  const int status = ::pclose(pipe);
  if (status != 0)
    throw ioError("`" + command + "` failed: " + out, {},
                  "check that Slurm's clients reach the controller (SLURM_CONF, sinfo)");
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out.substr(0, out.find(';'));
}

std::string arrayList(const std::vector<int>& tasks) {
  bool contiguous = true;
  for (std::size_t i = 1; i < tasks.size(); ++i) contiguous &= tasks[i] == tasks[i - 1] + 1;
  if (contiguous && tasks.size() > 1)
    return std::to_string(tasks.front()) + "-" + std::to_string(tasks.back());
  std::string out;
  for (const int t : tasks) out += (out.empty() ? "" : ",") + std::to_string(t);
  return out;
}

std::string afterEveryTask(const std::string& arrayId, const std::vector<int>& tasks) {
  std::string dependency;
  for (const int t : tasks)
    dependency += (dependency.empty() ? "afterok:" : ":") + arrayId + "_" + std::to_string(t);
  return dependency;
}

std::string taskCostLines(const fs::path& logs, const std::string& prefix, const std::string& label,
                          std::size_t tasks) {
  return "echo \"the " + label +
         "s, from the last run in each log:\"\n"
         "for task in $(seq 0 " +
         std::to_string(tasks - 1) +
         "); do\n"
         "  log=" +
         shellQuote(logs.string()) + "/" + prefix +
         "-$task.log\n"
         "  [ -e \"$log\" ] || { echo \"  " +
         label +
         " $task: no log\"; continue; }\n"
         "  awk -v t=\"$task\" '/^  process: CPU / { cpu = $3; mem = $7 }\n"
         "    END { if (cpu != \"\") printf \"  " +
         label +
         " %d: CPU %s s, peak memory %s MB\\n\", t, cpu, mem;\n"
         "          else printf \"  " +
         label +
         " %d: no summary in its log\\n\", t }' \"$log\"\n"
         "done | awk '{ print } $3 == \"CPU\" { cpu += $4; if ($8 + 0 > peak) peak = $8 + 0 }\n"
         "  END { printf \"  all: CPU %.1f s; the largest peak memory %.0f MB\\n\", cpu, peak }'\n";
}

namespace {

/// " --dependency=afterok:…" on every listed task of each (id, tasks), or "".
std::string afterEvery(const std::vector<std::pair<std::string, std::vector<int>>>& arrays) {
  std::string dependency;
  for (const auto& [id, tasks] : arrays) {
    if (tasks.empty()) continue;
    const std::string each = afterEveryTask(id, tasks);
    dependency += dependency.empty() ? each : each.substr(each.find(':'));
  }
  return dependency.empty() ? "" : " --dependency=" + dependency + " --kill-on-invalid-dep=yes";
}

}  // namespace

std::string ArrayThenJob::headCommand() const {
  if (headTasks.empty()) return "";
  return "sbatch --parsable --array=" + arrayList(headTasks) +
         (sbatchArgs.empty() ? "" : " " + sbatchArgs) + " " + shellQuote(arrayScript.string());
}

std::string ArrayThenJob::arrayCommand(const std::string& head) const {
  return "sbatch --parsable --array=" + arrayList(tasks) + afterEvery({{head, headTasks}}) +
         (sbatchArgs.empty() ? "" : " " + sbatchArgs) + " " + shellQuote(arrayScript.string());
}

std::string ArrayThenJob::afterCommand(const std::string& id, const std::string& head) const {
  return "sbatch --parsable" + afterEvery({{head, headTasks}, {id, tasks}}) +
         (sbatchArgs.empty() ? "" : " " + sbatchArgs) + " " + shellQuote(afterScript.string());
}

std::vector<std::string> ArrayThenJob::shellLines() const {
  std::vector<std::string> lines;
  if (!headTasks.empty()) lines.push_back("H=$(" + headCommand() + ")");
  if (!tasks.empty()) lines.push_back("A=$(" + arrayCommand("${H}") + ")");
  lines.push_back(afterCommand("${A}", "${H}"));
  return lines;
}

void ArrayThenJob::submit() {
  headId = headTasks.empty() ? "" : runForOutput(headCommand());
  arrayId = tasks.empty() ? "" : runForOutput(arrayCommand(headId));
  afterId = runForOutput(afterCommand(arrayId, headId));
}

ProcessCost processCost() {
  ::rusage usage{};
  if (::getrusage(RUSAGE_SELF, &usage) != 0) return {};
  const auto seconds = [](const ::timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  // Linux gives ru_maxrss in KiB.
  return {seconds(usage.ru_utime) + seconds(usage.ru_stime),
          static_cast<double>(usage.ru_maxrss) * 1024 / 1e6};
}

}  // namespace tinsmith::cli
