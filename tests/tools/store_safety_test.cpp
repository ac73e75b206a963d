// Nothing lost: what `tinsmith tile`, `merge` and `build` do to what is already
// at their output paths. A folder or archive that is not a tinsmith store is
// never emptied or replaced (not even the working folder); an option that is
// refused touches nothing; a run killed at any moment, a full disk, a file-size
// limit and a read-only filesystem leave the old store whole and readable,
// with the error naming the path (a merge leaves none of its stage's files);
// an archive another process holds locked is said to be in use, not foreign.
// Merge refuses an input as its output and a refined tile without all its
// children; --resume reuses a finished store.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;

const std::string kTinsmith = TINSMITH_BINARY;

/// A hill of 121 × 121 noisy spot heights 10 m apart: tiled at 0.5 m in
/// under a second, at 0.2 m in about two (long enough to be killed midway).
fs::path hillTin(const fs::path& dir) {
  const auto tin = dir / "hill.tin";
  const auto r = runTinsmith(
      "tin --points 'synthetic:grid?nx=121&ny=121&spacing=10&jitter=0.05&x0=430000&y0=4515000"
      "&surface=hill&z0=1600&scale=80&noise=0.5' --crs EPSG:26912 -q -o " +
      tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return tin;
}

std::string tileArgs(const fs::path& tin, double tolerance) {
  return "tile " + tin.string() + " --max-triangles 2048 --threads 1 -q --tolerance " +
         std::to_string(tolerance);
}

/// The shards of a job: the tiles above zoom 1 (top.3dtiles), then the
/// four zoom-1 subtrees (part0..3.3dtiles), in `dir`.
std::vector<std::string> makeShards(const fs::path& dir, const std::string& common) {
  std::vector<std::string> shards{(dir / "top.3dtiles").string()};
  auto r = runTinsmith(common + " --until-zoom 1 -o " + shards[0]);
  EXPECT_EQ(r.exitCode, 0) << r.err;
  for (int k = 0; k < 4; ++k) {
    shards.push_back((dir / ("part" + std::to_string(k) + ".3dtiles")).string());
    const std::string id = "1/" + std::to_string(k & 1) + "/" + std::to_string(k >> 1);
    r = runTinsmith(common + " --subtree " + id + " -o " + shards.back());
    EXPECT_EQ(r.exitCode, 0) << r.err;
  }
  return shards;
}

/// Every file under `path` (or the file itself, as ""), with its bytes.
using Snapshot = std::map<std::string, std::string>;
Snapshot snapshot(const fs::path& path) {
  Snapshot s;
  if (fs::is_regular_file(path)) {
    s[""] = readFile(path);
  } else if (fs::is_directory(path)) {
    for (const auto& e : fs::recursive_directory_iterator(path))
      if (e.is_regular_file()) s[e.path().lexically_relative(path).generic_string()] = readFile(e);
  }
  return s;
}

/// The names in a folder, sorted.
std::vector<std::string> namesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

bool readable(const fs::path& store) {
  return runTinsmith("info " + store.string()).exitCode == 0;
}

/// Runs `command` in a shell that execs it (so the pid is the command's) and
/// kills it with SIGKILL after `delay`, unless it ended before; returns
/// whether it was killed, and how long it ran.
std::pair<bool, double> runAndKill(const std::string& command, std::chrono::microseconds delay) {
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_RDWR);
    ::dup2(null, 0);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const auto until = start + delay;
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  int status = 0;
  while (std::chrono::steady_clock::now() < until) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return {false, elapsed()};
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return {WIFSIGNALED(status), elapsed()};
}

double secondsOf(const std::string& command) {
  const auto start = std::chrono::steady_clock::now();
  const auto r = runCommand(command);
  EXPECT_EQ(r.exitCode, 0) << command << "\n" << r.err;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Kills `command` (which writes `store`) at twelve moments spread over its
/// run time and checks after each that `store` is exactly `before` or
/// exactly `after` (never a mix, never missing) and readable; then runs it
/// whole and checks that nothing but `expectedNames` is left in the folder.
void killAtAnyMoment(const std::string& command, const fs::path& store, const Snapshot& before,
                     const Snapshot& after, const std::vector<std::string>& expectedNames) {
  // The run's duration sets the moments; a run that ends before its kill
  // (the machine got faster) shortens it and is tried again.
  double seconds = secondsOf(command);
  ASSERT_EQ(snapshot(store), after);
  // Put the old store back, then kill at each moment.
  int killed = 0;
  std::vector<double> moments = {0.02, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99};
  for (std::size_t m = 0, tries = 0; m < moments.size() && tries < 3 * moments.size(); ++tries) {
    const double fraction = moments[m];
    fs::remove_all(store);
    if (before.size() == 1 && before.count("")) {
      std::ofstream(store, std::ios::binary) << before.at("");
    } else {
      for (const auto& [key, bytes] : before) {
        fs::create_directories((store / key).parent_path());
        std::ofstream(store / key, std::ios::binary) << bytes;
      }
    }
    const auto delay = std::chrono::microseconds(static_cast<long>(fraction * seconds * 1e6));
    const auto [wasKilled, ran] = runAndKill(command, delay);
    if (wasKilled) {
      ++killed;
      ++m;
    } else {
      seconds = std::min(seconds, ran);
    }
    const Snapshot now = snapshot(store);
    EXPECT_TRUE(now == before || now == after)
        << "killed at " << fraction << " of the run: " << store << " holds " << now.size()
        << " files, a mix or nothing (before " << before.size() << ", after " << after.size()
        << ")";
    EXPECT_TRUE(readable(store)) << "killed at " << fraction;
  }
  EXPECT_GE(killed, 10) << "the run ended before most kills: nothing was tested";
  const auto whole = runCommand(command);
  ASSERT_EQ(whole.exitCode, 0) << whole.err;
  EXPECT_EQ(snapshot(store), after);
  EXPECT_EQ(namesIn(store.parent_path()), expectedNames);
}

TEST(StoreSafety, AFolderThatIsNotAStoreIsNeverEmptied) {
  const auto dir = scratchDir("safety-victim");
  const auto tin = hillTin(dir);
  fs::create_directories(dir / "victim" / "photos");
  std::ofstream(dir / "victim" / "thesis.tex") << "years of work";
  std::ofstream(dir / "victim" / "photos" / "a.jpg") << "jpeg";
  const Snapshot victim = snapshot(dir / "victim");
  auto r = runTinsmith(tileArgs(tin, 0.5) + " -o " + (dir / "victim").string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_NE(r.err.find("not a tinsmith tile store"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("victim"), std::string::npos) << r.err;
  EXPECT_EQ(snapshot(dir / "victim"), victim);
  EXPECT_FALSE(fs::exists(dir / "victim.partial"));

  // `-o .`: the working folder, which holds the input TIN.
  const Snapshot work = snapshot(dir);
  r = runCommand("cd " + dir.string() + " && " + kTinsmith + " " + tileArgs("hill.tin", 0.5) +
                 " -o .");
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_EQ(snapshot(dir), work);
  EXPECT_EQ(namesIn(dir), (std::vector<std::string>{"hill.tin", "victim"}));

  // The same for an archive's name taken by another program's file, and for
  // build's TIN beside the store.
  std::ofstream(dir / "other.3dtiles") << "not SQLite";
  r = runTinsmith(tileArgs(tin, 0.5) + " -o " + (dir / "other.3dtiles").string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_EQ(readFile(dir / "other.3dtiles"), "not SQLite");
}

TEST(StoreSafety, AFolderStoreIsReplacedWholeAndAnArchiveIsResumedFromWhenFinished) {
  const auto dir = scratchDir("safety-replace");
  const auto tin = hillTin(dir);
  const auto folder = dir / "site";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + folder.string()).exitCode, 0);
  const Snapshot coarse = snapshot(folder);
  ASSERT_TRUE(coarse.count("tinsmith/build.json"));
  auto r = runTinsmith(tileArgs(tin, 0.2) + " -o " + folder.string() + "/");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const Snapshot fine = snapshot(folder);
  EXPECT_NE(fine, coarse);
  EXPECT_GT(fine.size(), coarse.size());
  EXPECT_EQ(namesIn(dir), (std::vector<std::string>{"hill.tin", "site"}));
  // A fresh folder run gives the same files: nothing of the coarse run stays.
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.2) + " -o " + (dir / "fresh").string()).exitCode, 0);
  EXPECT_EQ(snapshot(dir / "fresh"), fine);

  // --resume on a finished archive keeps every tile and writes the same bytes.
  const auto archive = dir / "site.3dtiles";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + archive.string()).exitCode, 0);
  const std::string bytes = readFile(archive);
  r = runTinsmith(tileArgs(tin, 0.5) + " --resume --json -o " + archive.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["built"], 0);
  EXPECT_EQ(summary["kept"], summary["tiles"]);
  EXPECT_EQ(readFile(archive), bytes);
  // ... and a folder store the same.
  r = runTinsmith(tileArgs(tin, 0.2) + " --resume --json -o " + folder.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["built"], 0);
  EXPECT_EQ(snapshot(folder), fine);
}

TEST(StoreSafety, ARefusedOptionTouchesNothing) {
  const auto dir = scratchDir("safety-refused");
  const auto tin = hillTin(dir);
  const auto archive = dir / "site.3dtiles";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + archive.string()).exitCode, 0);
  const std::string bytes = readFile(archive);
  for (const std::string& bad :
       {tileArgs(tin, 0.5) + " --subtree 9/0/0", tileArgs(tin, 0.5) + " --subtree 1/5/0",
        tileArgs(tin, 0.3) + " --resume"}) {
    const auto r = runTinsmith(bad + " -o " + archive.string());
    EXPECT_EQ(r.exitCode, 2) << bad << ": " << r.err;
    EXPECT_EQ(readFile(archive), bytes) << bad;
    EXPECT_EQ(namesIn(dir), (std::vector<std::string>{"hill.tin", "site.3dtiles"})) << bad;
    // The resumed store's refusal says what differs.
    if (bad.ends_with("--resume")) {
      EXPECT_NE(r.err.find("with other options (tolerance 0.5 in it, 0.3 in this run)"),
                std::string::npos)
          << r.err;
    }
  }
  // A store of an older tinsmith (its build record's format) is refused by
  // --resume and by merge, naming the version, not "another TIN".
  {
    auto st = store::openStoreForWriting(archive, true);
    std::string build = *st->get("tinsmith/build.json");
    const std::string now = ingest::kTileBuildFormat;
    const auto at = build.find(now);
    ASSERT_NE(at, std::string::npos) << build;
    build.replace(at, now.size(), "tinsmith-tiles/1");
    st->put("tinsmith/build.json", build);
  }
  const std::string older = readFile(archive);
  auto r = runTinsmith(tileArgs(tin, 0.5) + " --resume -o " + archive.string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("by another version of tinsmith (its tiles are tinsmith-tiles/1, this "
                       "tinsmith makes " +
                       std::string(ingest::kTileBuildFormat) + ")"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(readFile(archive), older);
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + (dir / "now.3dtiles").string()).exitCode, 0);
  r = runTinsmith("merge -q " + (dir / "now.3dtiles").string() + " " + archive.string() + " -o " +
                  (dir / "merged.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("by another version of tinsmith"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "merged.3dtiles"));
  fs::remove(dir / "now.3dtiles");
  // Nor on a new output: no staging archive is left.
  r = runTinsmith(tileArgs(tin, 0.5) + " --subtree 9/0/0 -o " + (dir / "new.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(namesIn(dir), (std::vector<std::string>{"hill.tin", "site.3dtiles"}));
}

TEST(StoreSafety, MergeNeverWritesOverAnInputAndNeedsEveryChild) {
  const auto dir = scratchDir("safety-merge");
  const auto tin = hillTin(dir);
  const std::string common = tileArgs(tin, 0.5);
  ASSERT_EQ(runTinsmith(common + " -o " + (dir / "whole.3dtiles").string()).exitCode, 0);
  const std::vector<std::string> shards = makeShards(dir, common);
  const std::vector<std::string> parts(shards.begin() + 1, shards.end());
  const auto allNames = namesIn(dir);
  const std::string& top = shards[0];
  const std::string topBytes = readFile(top);

  // One of the four shards missing: refused, naming the child.
  auto r = runTinsmith("merge -q " + top + " " + parts[0] + " " + parts[1] + " " + parts[3] +
                       " -o " + (dir / "merged.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("1/0/1"), std::string::npos) << r.err;
  EXPECT_EQ(namesIn(dir), allNames);

  // An input as the output, by its name or another: refused, the input whole.
  for (const std::string& output : {top, (dir / "." / "top.3dtiles").string()}) {
    r = runTinsmith("merge -q " + top + " " + parts[0] + " " + parts[1] + " " + parts[2] + " " +
                    parts[3] + " -o " + output);
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_NE(r.err.find("also an input"), std::string::npos) << r.err;
    EXPECT_EQ(readFile(top), topBytes);
    EXPECT_EQ(namesIn(dir), allNames);
  }

  // All of them: the bytes of one run.
  r = runTinsmith("merge -q " + top + " " + parts[0] + " " + parts[1] + " " + parts[2] + " " +
                  parts[3] + " -o " + (dir / "merged.3dtiles").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readFile(dir / "merged.3dtiles"), readFile(dir / "whole.3dtiles"));
}

TEST(StoreSafety, AKilledTileLeavesTheOldStoreWhole) {
  const auto dir = scratchDir("safety-kill-tile");
  const auto tin = hillTin(dir);
  for (const std::string name : {"site.3dtiles", "site"}) {
    const auto store = dir / "stores" / name;
    fs::remove_all(dir / "stores");
    ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + store.string()).exitCode, 0);
    const Snapshot before = snapshot(store);
    const auto reference = dir / ("reference-" + name);
    ASSERT_EQ(runTinsmith(tileArgs(tin, 0.2) + " -o " + reference.string()).exitCode, 0);
    killAtAnyMoment(kTinsmith + " " + tileArgs(tin, 0.2) + " -o " + store.string(), store, before,
                    snapshot(reference), {name});
  }
}

TEST(StoreSafety, AKilledMergeOrBuildLeavesTheOldStoreWhole) {
  const auto dir = scratchDir("safety-kill-merge");
  const auto tin = hillTin(dir);
  fs::create_directories(dir / "out");
  const auto store = dir / "out" / "site.3dtiles";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + store.string()).exitCode, 0);
  const Snapshot before = snapshot(store);
  // Merge: the shards of the 0.2 m job.
  const std::string common = tileArgs(tin, 0.2);
  std::string shards;
  for (const std::string& shard : makeShards(dir, common)) shards += " " + shard;
  ASSERT_EQ(runTinsmith(common + " -o " + (dir / "whole.3dtiles").string()).exitCode, 0);
  const Snapshot after = snapshot(dir / "whole.3dtiles");
  killAtAnyMoment(kTinsmith + " merge -q " + shards + " -o " + store.string(), store, before, after,
                  {"site.3dtiles"});

  // Build: the store and the TIN beside it.
  fs::remove(store);
  const auto config = dir / "site.toml";
  std::ofstream(config)
      << "[project]\ncrs = \"EPSG:26912\"\n\n[[layer]]\npath = \"synthetic:grid?nx=121&ny=121"
         "&spacing=10&jitter=0.05&x0=430000&y0=4515000&surface=hill&z0=1600&scale=80&noise=0.5\"\n"
         "kind = \"points\"\ncrs = \"EPSG:26912\"\nname = \"hill\"\n\n[tiles]\nmax_triangles = "
         "2048\n";
  const std::string build =
      kTinsmith + " build " + config.string() + " -q --threads 1 -o " + store.string();
  ASSERT_EQ(runCommand(build + " --tolerance 0.5").exitCode, 0);
  const Snapshot oldStore = snapshot(store);
  const std::string oldTin = readFile(dir / "out" / "site.tin");
  ASSERT_EQ(runCommand(build + " --tolerance 0.2").exitCode, 0);
  const Snapshot newStore = snapshot(store);
  const std::string newTin = readFile(dir / "out" / "site.tin");
  ASSERT_EQ(oldTin, newTin);  // the TIN does not depend on the tile options
  // The kill loop restores the store only; the TIN must survive as it is.
  fs::remove(store);
  std::ofstream(store, std::ios::binary) << oldStore.at("");
  killAtAnyMoment(build + " --tolerance 0.2", store, oldStore, newStore,
                  {"site.3dtiles", "site.tin"});
  EXPECT_EQ(readFile(dir / "out" / "site.tin"), oldTin);
}

// A writer killed inside a transaction leaves a hot journal beside the
// archive; the next run must still recognise the archive as its own (it
// refused it, exit 5: "attempt to write a readonly database", when a kill
// came at that moment).
TEST(StoreSafety, AnArchiveWithAKilledWritersJournalIsStillReplaced) {
  const auto dir = scratchDir("safety-hot-journal");
  const auto tin = hillTin(dir);
  const auto store = dir / "site.3dtiles";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + store.string()).exitCode, 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {  // the writer: a transaction spilled into the file, then killed
    sqlite3* db = nullptr;
    sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr);
    sqlite3_exec(db,
                 "PRAGMA journal_mode = DELETE; PRAGMA cache_size = 1; BEGIN;"
                 "DELETE FROM media WHERE key = 'tileset.json';"
                 "WITH RECURSIVE n(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM n WHERE i < 40)"
                 " INSERT INTO media SELECT 'tiles/9/' || i || '/0.glb', zeroblob(100000) FROM n;",
                 nullptr, nullptr, nullptr);
    ::_exit(0);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(fs::exists(store.string() + "-journal"));
  const auto r = runTinsmith(tileArgs(tin, 0.2) + " -o " + store.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(readable(store));
}

TEST(StoreSafety, AnArchiveAnotherProcessHoldsLockedIsLeftAloneAndSaidSo) {
  // Another process (a run writing the archive, in SQLite's exclusive mode)
  // holds the store locked: the error says so and what to do, and never
  // asks for it to be moved away; the store is untouched.
  const auto dir = scratchDir("safety-locked");
  const auto tin = hillTin(dir);
  const auto store = dir / "site.3dtiles";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + store.string()).exitCode, 0);
  const std::string bytes = readFile(store);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(store.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "PRAGMA locking_mode = EXCLUSIVE; BEGIN EXCLUSIVE;", nullptr, nullptr,
                         nullptr),
            SQLITE_OK);
  const auto r = runTinsmith(tileArgs(tin, 0.2) + " -o " + store.string());
  sqlite3_exec(db, "ROLLBACK;", nullptr, nullptr, nullptr);
  sqlite3_close_v2(db);
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_NE(r.err.find(store.string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("locked by another process"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("wait for it to end"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("move what is there away"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(store), bytes);
  EXPECT_TRUE(readable(store));
}

TEST(StoreSafety, AFileSizeLimitIsAnErrorNamingTheFileAndTheOldStoreStays) {
  const auto dir = scratchDir("safety-ulimit");
  const auto tin = hillTin(dir);
  const auto store = dir / "site.3dtiles";
  ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + store.string()).exitCode, 0);
  const std::string bytes = readFile(store);
  // 1500 KiB: the 0.2 m archive (about 2.2 MB) cannot be written.
  const auto r = runCommand("ulimit -f 1500; exec " + kTinsmith + " " + tileArgs(tin, 0.2) +
                            " -o " + store.string());
  EXPECT_EQ(r.exitCode, 5) << r.err;
  EXPECT_NE(r.err.find(dir.string()), std::string::npos) << r.err;
  EXPECT_EQ(readFile(store), bytes);
  EXPECT_TRUE(readable(store));
}

/// A small tmpfs at `dir`, unmounted at the end; skips the test where this
/// process may not mount (not root).
class SmallFilesystem {
 public:
  SmallFilesystem(const fs::path& dir, std::size_t bytes) : dir_(dir) {
    fs::create_directories(dir);
    const std::string options = "size=" + std::to_string(bytes);
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, options.c_str()) == 0;
  }
  ~SmallFilesystem() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallFilesystem(const SmallFilesystem&) = delete;
  SmallFilesystem& operator=(const SmallFilesystem&) = delete;
  [[nodiscard]] bool mounted() const { return mounted_; }
  bool makeReadOnly() {
    return ::mount("tmpfs", dir_.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, nullptr) == 0;
  }

 private:
  fs::path dir_;
  bool mounted_ = false;
};

TEST(StoreSafety, AFullDiskOrAReadOnlyFilesystemLeavesTheOldStoreWhole) {
  const auto dir = scratchDir("safety-disk");
  const auto tin = hillTin(dir);
  // The old stores (about 1 MB) are made outside and copied in. The new
  // archive (2.2 MB) is staged with its WAL (measured: about 5.5 MB at the
  // peak) and then copied under its name: 3 MB fills up while staging, 7 MB
  // while copying. A folder store is only staged.
  const std::vector<std::pair<std::string, std::size_t>> cases = {
      {"site.3dtiles", 3}, {"site.3dtiles", 7}, {"site", 3}};
  for (const auto& [name, megabytes] : cases) {
    const auto old = dir / ("old-" + name);
    if (!fs::exists(old)) {
      ASSERT_EQ(runTinsmith(tileArgs(tin, 0.5) + " -o " + old.string()).exitCode, 0);
    }
    const auto mount = dir / ("disk-" + std::to_string(megabytes) + "-" + name);
    SmallFilesystem disk(mount, megabytes << 20);
    if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here (not root)";
    const auto store = mount / name;
    fs::copy(old, store, fs::copy_options::recursive);
    const Snapshot before = snapshot(store);
    const auto r = runTinsmith(tileArgs(tin, 0.2) + " -o " + store.string());
    EXPECT_EQ(r.exitCode, 5) << megabytes << " MB, " << name << ": " << r.err;
    EXPECT_NE(r.err.find(mount.string()), std::string::npos) << r.err;
    EXPECT_EQ(snapshot(store), before) << megabytes << " MB, " << name;
    EXPECT_TRUE(readable(store));
  }
  // A merge that fills the disk: the old store whole, and nothing of the
  // merge's stage left beside it (SQLite's -wal and -shm neither).
  {
    const auto shards = makeShards(dir, tileArgs(tin, 0.2));
    const auto mount = dir / "disk-merge";
    SmallFilesystem disk(mount, std::size_t(3) << 20);
    ASSERT_TRUE(disk.mounted());
    const auto store = mount / "site.3dtiles";
    fs::copy(dir / "old-site.3dtiles", store);
    const std::string bytes = readFile(store);
    std::string inputs;
    for (const auto& s : shards) inputs += " " + s;
    const auto r = runTinsmith("merge" + inputs + " -q -o " + store.string());
    EXPECT_EQ(r.exitCode, 5) << r.err;
    EXPECT_NE(r.err.find(mount.string()), std::string::npos) << r.err;
    EXPECT_EQ(readFile(store), bytes);
    EXPECT_EQ(namesIn(mount), std::vector<std::string>{"site.3dtiles"});
  }
  const auto mount = dir / "read-only";
  SmallFilesystem disk(mount, std::size_t(8) << 20);
  ASSERT_TRUE(disk.mounted());
  const auto store = mount / "site.3dtiles";
  fs::copy(dir / "old-site.3dtiles", store);
  const std::string bytes = readFile(store);
  ASSERT_TRUE(disk.makeReadOnly());
  for (const std::string& command : {tileArgs(tin, 0.2) + " -o " + store.string(),
                                     tileArgs(tin, 0.5) + " --resume -o " + store.string()}) {
    const auto r = runTinsmith(command);
    EXPECT_EQ(r.exitCode, 5) << r.err;
    EXPECT_NE(r.err.find(mount.string()), std::string::npos) << r.err;
    EXPECT_EQ(readFile(store), bytes);
  }
  EXPECT_TRUE(readable(store));
}

}  // namespace
}  // namespace tinsmith::test
