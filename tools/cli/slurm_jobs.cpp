#include "tools/cli/slurm_jobs.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
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
  std::error_code ec;
  if (executable)
    fs::permissions(temp, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec,
                    fs::perm_options::add, ec);
  if (!ec) fs::rename(temp, path, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw ioError("cannot write '" + path.string() + "'", fileLocation(path.string()),
                  "check that the work folder is writable");
  }
}

void makeFolder(const fs::path& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder))
    throw ioError("cannot create the folder '" + folder.string() + "'" +
                      (ec ? ": " + ec.message() : std::string()),
                  fileLocation(folder.string()),
                  "give a --workdir where you may write, on a filesystem the nodes share");
}

namespace {

/// Runs `command` (/bin/sh) and returns pclose's status, its stdout in `out`;
/// −1 when it cannot be started.
int runReading(const std::string& command, std::string& out) {
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return -1;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) out.append(buffer, n);
  return ::pclose(pipe);
}

}  // namespace

std::string runForOutput(const std::string& command) {
  // Its stderr apart: sbatch (and a site's job_submit plugin) may warn there
  // on success, and only stdout holds the id.
  char errName[] = "/tmp/tinsmith-sbatch-XXXXXX";
  const int errFd = ::mkstemp(errName);
  if (errFd < 0) throw ioError("cannot make a temporary file in /tmp", {}, "check /tmp");
  ::close(errFd);
  std::string out;
  const int status = runReading(command + " 2>" + shellQuote(errName), out);
  if (status == -1) {
    ::unlink(errName);
    throw ioError("cannot run: " + command, {}, "check that sbatch is on PATH");
  }
  std::string err;
  {
    std::ifstream in(errName, std::ios::binary);
    err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ::unlink(errName);
  const auto trimmed = [](std::string t) {
    while (!t.empty() && (t.back() == '\n' || t.back() == '\r' || t.back() == ' ')) t.pop_back();
    return t;
  };
  if (status != 0)
    throw ioError("`" + command + "` failed: " + trimmed(err + out), {},
                  "check the sbatch arguments and that Slurm's clients reach the controller "
                  "(SLURM_CONF, sinfo)");
  // --parsable: "ID" or "ID;CLUSTER" on the last line.
  out = trimmed(out);
  const std::string last =
      out.substr(out.find_last_of('\n') == std::string::npos ? 0 : out.find_last_of('\n') + 1);
  const std::string id = last.substr(0, last.find(';'));
  if (id.empty() || !std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; }))
    throw ioError("`" + command + "` printed no job id: " + trimmed(out + "\n" + err), {},
                  "check sbatch --parsable by hand");
  return id;
}

int maxArraySize() {
  std::string out;
  if (runReading("scontrol show config 2>/dev/null", out) != 0) return 0;
  const std::size_t at = out.find("MaxArraySize");
  if (at == std::string::npos) return 0;
  const std::size_t eq = out.find('=', at);
  if (eq == std::string::npos) return 0;
  return std::atoi(out.c_str() + eq + 1);
}

std::vector<std::string> queuedJobs(const std::vector<std::string>& ids) {
  std::vector<std::string> out;
  if (ids.empty()) return out;
  std::string listed;
  if (runReading("squeue -h -o %i 2>/dev/null", listed) != 0) return out;
  std::istringstream lines(listed);
  for (std::string line; std::getline(lines, line);) {
    // "17", "18_3" or "18_[4-9]": the job, or a task of array job 18.
    const std::string job = line.substr(0, line.find('_'));
    if (std::find(ids.begin(), ids.end(), job) != ids.end() &&
        std::find(out.begin(), out.end(), job) == out.end())
      out.push_back(job);
  }
  return out;
}

void refuseWhileQueued(const nlohmann::ordered_json& plan) {
  if (!plan.is_object() || !plan.contains("submissions") || !plan["submissions"].is_array() ||
      plan["submissions"].empty())
    return;
  std::vector<std::string> submitted;
  for (const auto& [key, value] : plan["submissions"].back().items())
    if (value.is_string()) submitted.push_back(value.get<std::string>());
  const auto queued = queuedJobs(submitted);
  if (queued.empty()) return;
  std::string jobs;
  for (const auto& id : queued) jobs += (jobs.empty() ? "" : " ") + id;
  throw usageError("jobs of this job folder's last submission are still queued or running: " + jobs,
                   "wait for them (squeue), or cancel them (scancel " + jobs +
                       "), then submit again with --resume");
}

nlohmann::ordered_json submitAndRecord(ArrayThenJob& jobs, nlohmann::ordered_json plan,
                                       const std::filesystem::path& planPath,
                                       const std::string& afterKey, bool submit) {
  if (!plan.contains("submissions") || !plan["submissions"].is_array())
    plan["submissions"] = nlohmann::ordered_json::array();
  nlohmann::ordered_json submission;
  std::vector<int> tasks = jobs.headTasks;
  tasks.insert(tasks.end(), jobs.tasks.begin(), jobs.tasks.end());
  submission["tasks"] = tasks;
  writeAtomically(planPath, plan.dump(2) + "\n", false);
  if (!submit) return submission;
  const auto record = [&] {
    for (const auto& [key, id] : {std::pair<std::string, const std::string*>{"top", &jobs.headId},
                                  {"array", &jobs.arrayId},
                                  {afterKey, &jobs.afterId}})
      if (!id->empty()) submission[key] = *id;
    nlohmann::ordered_json written = plan;
    written["submissions"].push_back(submission);
    writeAtomically(planPath, written.dump(2) + "\n", false);
  };
  try {
    jobs.submit();
  } catch (const Error&) {
    if (!jobs.headId.empty() || !jobs.arrayId.empty()) record();
    throw;
  }
  record();
  return submission;
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

namespace {

/// " --output=LOG --open-mode=append": the log on the command line, where
/// the shell quotes it (an #SBATCH line takes no path with a space or a
/// quote); a resubmitted task's log follows its failed one.
std::string logArguments(const fs::path& log) {
  return " --output=" + shellQuote(log.string()) + " --open-mode=append";
}

}  // namespace

std::string ArrayThenJob::headCommand() const {
  if (headTasks.empty()) return "";
  return "sbatch --parsable --array=" + arrayList(headTasks) + logArguments(arrayLog) +
         (sbatchArgs.empty() ? "" : " " + sbatchArgs) + " " + shellQuote(arrayScript.string());
}

std::string ArrayThenJob::arrayCommand(const std::string& head) const {
  return "sbatch --parsable --array=" + arrayList(tasks) + afterEvery({{head, headTasks}}) +
         logArguments(arrayLog) + (sbatchArgs.empty() ? "" : " " + sbatchArgs) + " " +
         shellQuote(arrayScript.string());
}

std::string ArrayThenJob::afterCommand(const std::string& id, const std::string& head) const {
  return "sbatch --parsable" + afterEvery({{head, headTasks}, {id, tasks}}) +
         logArguments(afterLog) + (sbatchArgs.empty() ? "" : " " + sbatchArgs) + " " +
         shellQuote(afterScript.string());
}

std::vector<std::string> ArrayThenJob::shellLines() const {
  std::vector<std::string> lines;
  if (!headTasks.empty()) lines.push_back("H=$(" + headCommand() + ")");
  if (!tasks.empty()) lines.push_back("A=$(" + arrayCommand("${H}") + ")");
  lines.push_back(afterCommand("${A}", "${H}"));
  return lines;
}

void ArrayThenJob::submit() {
  const int largest =
      std::max(headTasks.empty() ? 0 : headTasks.back(), tasks.empty() ? 0 : tasks.back());
  if (const int limit = maxArraySize(); limit > 0 && largest >= limit)
    throw usageError("the cluster's MaxArraySize is " + std::to_string(limit) +
                         " (array task ids below it), and this job's tasks go to " +
                         std::to_string(largest),
                     "ask for fewer tasks (a smaller --shard-zoom, larger blocks), or ask the "
                     "cluster's admins to raise MaxArraySize; nothing was submitted");
  try {
    if (!headTasks.empty()) headId = runForOutput(headCommand());
    if (!tasks.empty()) arrayId = runForOutput(arrayCommand(headId));
    afterId = runForOutput(afterCommand(arrayId, headId));
  } catch (const Error& e) {
    std::string queued;
    for (const auto& id : {headId, arrayId})
      if (!id.empty()) queued += (queued.empty() ? "" : " ") + id;
    if (queued.empty()) throw;
    throw ioError(e.problem() + "; already queued: job " + queued, {},
                  "cancel it (scancel " + queued +
                      ") or let it run, then submit again with --resume --submit");
  }
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
