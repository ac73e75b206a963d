// `tinsmith slurm` without a cluster: the scripts it writes run as Slurm
// would run them (each array task with its SLURM_ARRAY_TASK_ID, then the
// merge), and the merged store has the bytes of one `tinsmith tile` run —
// also where subtrees hold no terrain or lie under a tile that meets the
// tolerance (shards built without their ancestors, which the merge leaves
// out). Its work folder is refused when it holds something else or another
// job's plan.
// The same job on a real one-node Slurm cluster: tests/slurm.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tiles/tiling_plan.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;

/// `tinsmith tin` of a synthetic hill at UTM 12N into `tin`; `grid` gives its
/// nx, ny and spacing (and any other key the generator takes, e.g. noise).
CommandResult makeHillTin(const fs::path& tin, const std::string& grid) {
  return runTinsmith(
      "tin --points 'synthetic:grid?" + grid +
      "&x0=430000&y0=4515000&surface=hill&z0=1600&scale=80' --crs EPSG:26912 -q -o " +
      tin.string());
}

/// Runs every task of `workdir`'s shard.sh, then its merge.sh, as Slurm would.
void runAsSlurmWould(const fs::path& workdir, int tasks) {
  for (int k = 0; k < tasks; ++k) {
    // In braces: runCommand's own stderr redirect, added at the end, is not the log's.
    const auto r = runCommand(
        "{ SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " + (workdir / "shard.sh").string() +
        " >" + (workdir / "logs" / ("shard-" + std::to_string(k) + ".log")).string() + " 2>&1; }");
    EXPECT_EQ(r.exitCode, 0) << "task " << k << ": "
                             << readFile(workdir / "logs" /
                                         ("shard-" + std::to_string(k) + ".log"));
  }
  const auto merge = runCommand("{ bash " + (workdir / "merge.sh").string() + " >" +
                                (workdir / "logs" / "merge.log").string() + " 2>&1; }");
  EXPECT_EQ(merge.exitCode, 0) << readFile(workdir / "logs" / "merge.log");
}

/// `tinsmith slurm`'s job for `tin` with `options` at `shardZoom`, in
/// dir/work<shardZoom>, run as Slurm would: its merged store has the bytes
/// of dir/one.3dtiles (one `tinsmith tile` with the same options).
void expectShardsGiveOneRunsBytes(const fs::path& dir, const fs::path& tin,
                                  const std::string& options, int shardZoom) {
  SCOPED_TRACE("shard zoom " + std::to_string(shardZoom));
  const fs::path work = dir / ("work" + std::to_string(shardZoom));
  const fs::path merged = dir / ("merged" + std::to_string(shardZoom) + ".3dtiles");
  const auto planned =
      runTinsmith("slurm " + tin.string() + options + " --shard-zoom " + std::to_string(shardZoom) +
                  " --workdir " + work.string() + " -o " + merged.string());
  ASSERT_EQ(planned.exitCode, 0) << planned.err;
  runAsSlurmWould(work, 1 + (1 << (2 * shardZoom)));
  EXPECT_EQ(readFile(merged), readFile(dir / "one.3dtiles"));
}

TEST(SlurmCli, TheScriptsShardAndMergeIntoTheBytesOfOneRun) {
  const fs::path dir = scratchDir("slurm-cli");
  // 1.2 km × 0.4 km: the square's north half holds no terrain, so 8 of the
  // 16 subtrees at zoom 2 are not in the pyramid.
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=121&ny=41&spacing=10&noise=0.5").exitCode, 0);
  const std::string options = " --tolerance 0.2 --max-triangles 512";
  ASSERT_EQ(
      runTinsmith("tile " + tin.string() + options + " -q -o " + (dir / "one.3dtiles").string())
          .exitCode,
      0);

  const fs::path work = dir / "work";
  const auto planned =
      runTinsmith("slurm " + tin.string() + options + " --shard-zoom 2 --json" + " --workdir " +
                  work.string() + " -o " + (dir / "merged.3dtiles").string());
  ASSERT_EQ(planned.exitCode, 0) << planned.err;
  const auto out = nlohmann::json::parse(planned.out);
  EXPECT_EQ(out.at("tasks").size(), 17u);
  // Task 0 (the plan and the top) alone, the subtrees after it, the merge
  // after every task.
  const auto commands = out.at("commands").get<std::vector<std::string>>();
  ASSERT_EQ(commands.size(), 3u) << planned.out;
  // The logs' paths on the command line, quoted by the shell.
  EXPECT_EQ(
      commands[0].rfind("H=$(sbatch --parsable --array=0 --output='" +
                            (work / "logs" / "shard-%a.log").string() + "' --open-mode=append '",
                        0),
      0u)
      << commands[0];
  EXPECT_NE(commands[2].find("--output='" + (work / "logs" / "merge.log").string() + "'"),
            std::string::npos)
      << commands[2];
  EXPECT_NE(commands[1].find("--array=1-16 --dependency=afterok:${H}_0 --kill-on-invalid-dep=yes"),
            std::string::npos)
      << commands[1];
  EXPECT_NE(commands[2].find("--dependency=afterok:${H}_0:${A}_1:${A}_2:"), std::string::npos)
      << commands[2];
  // tinsmith slurm only writes the scripts: task 0 plans.
  EXPECT_FALSE(fs::exists(work / "tiler.plan"));
  // A subtree run before task 0 finds no plan and says so.
  const auto early = runCommand("SLURM_ARRAY_TASK_ID=1 bash " + (work / "shard.sh").string());
  EXPECT_NE(early.exitCode, 0);
  EXPECT_NE(early.err.find("tiler.plan"), std::string::npos) << early.err;
  EXPECT_FALSE(fs::exists(work / "shards" / "1.3dtiles"));
  // Every subtree is built (without its ancestors); the merge leaves out the
  // 8 that hold no terrain, as one run never builds them.
  runAsSlurmWould(work, 17);
  EXPECT_EQ(readFile(dir / "merged.3dtiles"), readFile(dir / "one.3dtiles"));
  // The merge's log ends with what each shard cost, from the shards' logs.
  const std::string mergeLog = readFile(work / "logs" / "merge.log");
  for (int k = 0; k < 17; ++k)
    EXPECT_NE(mergeLog.find("  shard " + std::to_string(k) + ": CPU "), std::string::npos)
        << "shard " << k << " in:\n"
        << mergeLog;
  EXPECT_NE(mergeLog.find("  all: CPU "), std::string::npos) << mergeLog;
  int stores = 0;
  for (const auto& e : fs::directory_iterator(work / "shards"))
    stores += e.path().extension() == ".3dtiles";
  EXPECT_EQ(stores, 17);
  // The TIN is in the top shard alone, which the merge takes it from.
  for (int k = 0; k < 17; ++k) {
    const auto shard =
        store::openStoreForReading(work / "shards" / (std::to_string(k) + ".3dtiles"));
    EXPECT_EQ(shard->contains("tinsmith/terrain.tin"), k == 0) << "shard " << k;
  }
  // Task 0 wrote the job's tiling plan, which every subtree took: the
  // pyramid of the one run.
  const auto one =
      nlohmann::json::parse(runTinsmith("info --json " + (dir / "one.3dtiles").string()).out);
  EXPECT_EQ(ingest::readTilingPlan(work / "tiler.plan").tiler.finestZoom,
            one.at("finestZoom").get<int>());
  const std::string script = readFile(work / "shard.sh");
  EXPECT_NE(script.find("--write-plan '" + (work / "tiler.plan").string() + "'"), std::string::npos)
      << script;
  EXPECT_NE(script.find("--plan '" + (work / "tiler.plan").string() + "'"), std::string::npos);

  // The same folder for another job, or a folder of other files: refused.
  auto r = runTinsmith("slurm " + tin.string() + " --tolerance 0.5 --shard-zoom 2 --workdir " +
                       work.string() + " -o " + (dir / "other.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("plan of another job"), std::string::npos) << r.err;
  fs::create_directories(dir / "mine");
  std::ofstream(dir / "mine" / "notes.txt") << "mine";
  r = runTinsmith("slurm " + tin.string() + options + " --shard-zoom 2 --workdir " +
                  (dir / "mine").string() + " -o " + (dir / "x.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_EQ(readFile(dir / "mine" / "notes.txt"), "mine");
  // Terrain is not sharded; --resume needs --submit.
  EXPECT_EQ(runTinsmith("slurm " + tin.string() + " --scheme both --shard-zoom 1 --workdir " +
                        (dir / "w2").string() + " -o " + (dir / "y.3dtiles").string())
                .exitCode,
            2);
  EXPECT_EQ(runTinsmith("slurm " + tin.string() + " --resume --shard-zoom 1 --workdir " +
                        (dir / "w3").string() + " -o " + (dir / "z.3dtiles").string())
                .exitCode,
            2);
}

// tinsmith slurm-tin: the points prepared here, block.sh run for every task
// and assemble.sh after them, as Slurm would: the .tin of `tinsmith tin
// --block-points` on one machine, byte for byte. A missing task stops the
// assembly, naming it and what to run.
TEST(SlurmCli, AnyShardZoomGivesTheBytesOfOneRunOnCliffsAndBreakLines) {
  // The hill crossed by three random break lines whose z is far below it:
  // cliffs of over 1 km at every line, tiles that refine to zoom 10, and
  // lines that cross the subtrees' sides. One run, then the job at shard
  // zooms 1 (5 tasks) and 3 (65 tasks, deeper than the merge test's 2).
  const fs::path dir = scratchDir("slurm-cli-any-zoom");
  const fs::path tin = dir / "site.tin";
  const auto built = runTinsmith(
      "tin --points 'synthetic:grid?nx=121&ny=41&spacing=10&noise=0.5&x0=430000&y0=4515000"
      "&surface=hill&z0=1600&scale=80' --breaklines 'synthetic:lines?layout=random&n=3&vertices=3"
      "&seed=5&width=1200&height=400&x0=430000&y0=4515000' --crs EPSG:26912 -q -o " +
      tin.string());
  ASSERT_EQ(built.exitCode, 0) << built.err;
  const std::string options = " --tolerance 0.2 --max-triangles 512 -q";
  const auto one =
      runTinsmith("tile " + tin.string() + options + " -o " + (dir / "one.3dtiles").string());
  ASSERT_EQ(one.exitCode, 0) << one.err;
  for (const int zoom : {1, 3}) expectShardsGiveOneRunsBytes(dir, tin, options, zoom);
}

TEST(SlurmCli, ShardsAcrossTheAntimeridianGiveTheBytesOfOneRun) {
  // 100 km × 100 km in UTM 60S, about 180° E ± 0.5° (Fiji): the subtrees'
  // sides and the pyramid's middle cross the antimeridian, where longitude
  // jumps from 180 to −180.
  const fs::path dir = scratchDir("slurm-cli-antimeridian");
  const fs::path tin = dir / "site.tin";
  const auto built = runTinsmith(
      "tin --points 'synthetic:grid?nx=201&ny=201&spacing=500&x0=780000&y0=8080000"
      "&surface=hill&z0=300&scale=400&noise=0.5' --crs EPSG:32760 -q -o " +
      tin.string());
  ASSERT_EQ(built.exitCode, 0) << built.err;
  const std::string options = " --tolerance 2 --max-triangles 512 -q";
  const auto one =
      runTinsmith("tile " + tin.string() + options + " -o " + (dir / "one.3dtiles").string());
  ASSERT_EQ(one.exitCode, 0) << one.err;
  const auto root = store::openStoreForReading(dir / "one.3dtiles")->get("tileset.json");
  ASSERT_TRUE(root);
  const auto region = nlohmann::json::parse(*root)["root"]["boundingVolume"]["region"];
  EXPECT_GT(region[0].get<double>(), region[2].get<double>()) << region;  // west > east
  expectShardsGiveOneRunsBytes(dir, tin, options, 2);
}

TEST(SlurmCli, ShardsOfAWideAlbersMosaicGiveTheBytesOfOneRun) {
  // 3 000 km by 900 km in CONUS Albers, which bends its straight lines away
  // from the ground: task 0 and every subtree plan chord sag with the same
  // radius, measured over the part of a tile's square the whole TIN's box
  // covers (the plan's box; WideArea.AStripsTilesTakeTheBendingOfTheGroundTheyCover
  // shows a shard's own part would give another).
  const fs::path dir = scratchDir("slurm-cli-albers");
  const fs::path tin = dir / "site.tin";
  const auto built = runTinsmith(
      "tin --points 'synthetic:grid?nx=101&ny=31&spacing=30000&x0=-2000000&y0=300000"
      "&surface=hill&z0=300&scale=2000&noise=5' --crs EPSG:5070 -q -o " +
      tin.string());
  ASSERT_EQ(built.exitCode, 0) << built.err;
  const std::string options = " --tolerance 20 --max-triangles 4096 -q";
  const auto one =
      runTinsmith("tile " + tin.string() + options + " -o " + (dir / "one.3dtiles").string());
  ASSERT_EQ(one.exitCode, 0) << one.err;
  expectShardsGiveOneRunsBytes(dir, tin, options, 1);
}

TEST(SlurmCli, ABlockByBlockTinFromItsScriptsHasOneMachinesBytes) {
  const fs::path dir = scratchDir("slurm-cli-tin");
  const std::string points =
      " --points 'synthetic:random?n=20000&seed=3&width=2000&height=1500&x0=431000&y0=4512000'"
      " --crs EPSG:26912 --block-points 1500 --max-circumradius 60";
  ASSERT_EQ(runTinsmith("tin" + points + " -q -o " + (dir / "one.tin").string()).exitCode, 0);
  const fs::path work = dir / "work";
  auto r = runTinsmith("slurm-tin" + points + " --json --workdir " + work.string() + " -o " +
                       (dir / "cluster.tin").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto out = nlohmann::json::parse(r.out);
  const int tasks = out.at("blockTasks").get<int>();
  ASSERT_GE(tasks, 9);
  EXPECT_NE(out.at("commands")[0].get<std::string>().find("sbatch --parsable --array=0-" +
                                                          std::to_string(tasks - 1)),
            std::string::npos);
  EXPECT_NE(out.at("commands")[1].get<std::string>().find("afterok:${A}_0:${A}_1"),
            std::string::npos);
  const auto runTask = [&](int k) {
    return runCommand(
        "{ SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " + (work / "block.sh").string() +
        " >>" + (work / "logs" / ("block-" + std::to_string(k) + ".log")).string() + " 2>&1; }");
  };
  const auto assemble = [&] {
    return runCommand("{ bash " + (work / "assemble.sh").string() + " >" +
                      (work / "logs" / "assemble.log").string() + " 2>&1; }");
  };
  for (int k = 1; k < tasks; ++k) EXPECT_EQ(runTask(k).exitCode, 0) << "task " << k;
  EXPECT_NE(assemble().exitCode, 0);
  const std::string failed = readFile(work / "logs" / "assemble.log");
  EXPECT_NE(failed.find("block task 0 of " + std::to_string(tasks) + " has no triangles"),
            std::string::npos)
      << failed;
  EXPECT_FALSE(fs::exists(dir / "cluster.tin"));
  // The same job again: refused without --resume (its blocks are there).
  r = runTinsmith("slurm-tin" + points + " --workdir " + work.string() + " -o " +
                  (dir / "cluster.tin").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("--resume"), std::string::npos) << r.err;
  EXPECT_EQ(runTask(0).exitCode, 0);
  EXPECT_EQ(assemble().exitCode, 0) << readFile(work / "logs" / "assemble.log");
  EXPECT_EQ(readFile(dir / "cluster.tin"), readFile(dir / "one.tin"));
  const std::string log = readFile(work / "logs" / "assemble.log");
  for (int k = 0; k < tasks; ++k)
    EXPECT_NE(log.find("  task " + std::to_string(k) + ": CPU "), std::string::npos) << log;
  // Another job's arguments in this folder, and --resume without --submit.
  std::string other = points;
  other.replace(other.find("circumradius 60"), 15, "circumradius 70");
  r = runTinsmith("slurm-tin" + other + " --workdir " + work.string() + " -o " +
                  (dir / "cluster.tin").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("another job"), std::string::npos) << r.err;
  EXPECT_EQ(runTinsmith("slurm-tin" + points + " --resume --workdir " + work.string() + " -o " +
                        (dir / "cluster.tin").string())
                .exitCode,
            2);
}

TEST(SlurmCli, AnOlderFormatTinIsRefusedWithWhatToDo) {
  // Its shards could not name it as the plan does (by its bytes in the
  // current format), nor read their parts through the index's summary.
  const fs::path dir = scratchDir("slurm-cli-format-1");
  const fs::path tin = dir / "hill.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=21&ny=21&spacing=10").exitCode, 0);
  // The same TIN as format 1: the sections without the block index, with
  // the header of version 1.
  const TinData whole = ingest::readTinFile(tin);
  std::uint64_t payload = 4 + whole.crs.size() + 8 + 24 * whole.vertices.size() + 8 +
                          12 * whole.triangles.size() + 8 + 8 + 12 * whole.constrainedEdges.size();
  for (const auto& f : whole.features) payload += 5 + f.source.size();
  std::string bytes = readFile(tin).substr(0, ingest::kTinHeaderSize + payload);
  const auto put = [&bytes](std::size_t at, std::uint64_t value, int size) {
    for (int i = 0; i < size; ++i) bytes[at + i] = static_cast<char>(value >> (8 * i));
  };
  put(8, 1, 4);
  put(16, payload, 8);
  put(24, ingest::crc32(std::string_view(bytes).substr(ingest::kTinHeaderSize)), 4);
  put(28, ingest::crc32(std::string_view(bytes).substr(0, 28)), 4);
  const fs::path old = dir / "old.tin";
  std::ofstream(old, std::ios::binary) << bytes;
  ASSERT_EQ(ingest::readTinFileHeader(old).version, 1u);
  const auto r =
      runTinsmith("slurm " + old.string() + " --tolerance 0.5 --shard-zoom 1 --workdir " +
                  (dir / "work").string() + " -o " + (dir / "out.3dtiles").string());
  EXPECT_NE(r.exitCode, 0);
  EXPECT_NE(r.err.find("old.tin"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("format version 1"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tinsmith export"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "work"));
  // A shard given such a file, with the plan of the same TIN, refuses it
  // too and says the same.
  const fs::path plan = dir / "tiler.plan";
  ASSERT_EQ(runTinsmith("tile " + tin.string() + " --tolerance 0.5 --until-zoom 1 --write-plan " +
                        plan.string() + " -q -o " + (dir / "top.3dtiles").string())
                .exitCode,
            0);
  const auto shard =
      runTinsmith("tile " + old.string() + " --tolerance 0.5 --plan " + plan.string() +
                  " --subtree 1/0/0 --unchecked-ancestors -o " + (dir / "shard.3dtiles").string());
  EXPECT_NE(shard.exitCode, 0);
  EXPECT_NE(shard.err.find("format version 1"), std::string::npos) << shard.err;
  EXPECT_NE(shard.err.find("tinsmith export"), std::string::npos) << shard.err;
  EXPECT_FALSE(fs::exists(dir / "shard.3dtiles"));
  // What it says to do: the export gives the TIN's bytes in this format,
  // which the job takes.
  const fs::path again = dir / "again.tin";
  const auto exported =
      runTinsmith("export " + old.string() + " --format tin -o " + again.string());
  ASSERT_EQ(exported.exitCode, 0) << exported.err;
  EXPECT_EQ(readFile(again), readFile(tin));
  EXPECT_EQ(runTinsmith("slurm " + again.string() + " --tolerance 0.5 --shard-zoom 1 --workdir " +
                        (dir / "work").string() + " -o " + (dir / "out.3dtiles").string())
                .exitCode,
            0);
}

TEST(SlurmCli, ASubtreeOutsideThePyramidIsAnErrorUnlessEmptyIsOk) {
  const fs::path dir = scratchDir("slurm-empty-ok");
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=121&ny=41&spacing=10").exitCode, 0);
  // 2/3/3 lies in the square's north half, where the TIN is not.
  const std::string tile = "tile " + tin.string() +
                           " --tolerance 0.2 --max-triangles 512 --subtree 2/3/3 -o " +
                           (dir / "s.3dtiles").string();
  auto r = runTinsmith(tile);
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("holds no terrain"), std::string::npos) << r.err;
  r = runTinsmith(tile + " --empty-ok");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("nothing to build"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "s.3dtiles"));
  EXPECT_EQ(runTinsmith("tile " + tin.string() + " --empty-ok -o " + (dir / "t.3dtiles").string())
                .exitCode,
            2);  // --empty-ok goes with --subtree
}

TEST(SlurmCli, TheTopTaskWritesThePlanAndARerunWritesTheSameBytes) {
  const fs::path dir = scratchDir("slurm-top");
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=101&ny=101&spacing=10&noise=0.5").exitCode, 0);
  const fs::path work = dir / "work";
  const auto planned = runTinsmith("slurm " + tin.string() +
                                   " --tolerance 0.2 --shard-zoom 1 --threads 1 -q --workdir " +
                                   work.string() + " -o " + (dir / "merged.3dtiles").string());
  ASSERT_EQ(planned.exitCode, 0) << planned.err;
  // Task 0 plans and tiles; run again (a resubmitted top: its subtrees may
  // have read the first plan), it writes the same plan, byte for byte.
  const std::string top = "SLURM_ARRAY_TASK_ID=0 bash " + (work / "shard.sh").string();
  const auto first = runCommand(top);
  ASSERT_EQ(first.exitCode, 0) << first.err;
  const std::string plan = readFile(work / "tiler.plan");
  ASSERT_FALSE(plan.empty());
  EXPECT_NO_THROW((void)ingest::readTilingPlan(work / "tiler.plan"));
  fs::remove_all(work / "shards" / "0.3dtiles");
  const auto second = runCommand(top);
  ASSERT_EQ(second.exitCode, 0) << second.err;
  EXPECT_EQ(readFile(work / "tiler.plan"), plan);
  // --write-plan is for the top (--until-zoom), without a plan given.
  EXPECT_EQ(runTinsmith("tile " + tin.string() + " --tolerance 0.2 --write-plan " +
                        (dir / "p.plan").string() + " -o " + (dir / "t.3dtiles").string())
                .exitCode,
            2);
  EXPECT_EQ(runTinsmith("tile " + tin.string() + " --tolerance 0.2 --until-zoom 1 --plan " +
                        (work / "tiler.plan").string() + " --write-plan " +
                        (dir / "p.plan").string() + " -o " + (dir / "t.3dtiles").string())
                .exitCode,
            2);
  EXPECT_FALSE(fs::exists(dir / "p.plan"));
  EXPECT_FALSE(fs::exists(dir / "t.3dtiles"));
}

TEST(SlurmCli, MergeLeavesOutSubtreesUnderATileThatDoesNotRefine) {
  const fs::path dir = scratchDir("slurm-unchecked");
  // 640 m square: a plane in the west half, a rippled hill in the east. The
  // west zoom-1 tiles meet the tolerance and have no children, yet their
  // zoom-2 subtrees hold terrain.
  {
    std::ofstream xyz(dir / "site.xyz");
    xyz.precision(10);
    for (int j = 0; j <= 64; ++j)
      for (int i = 0; i <= 64; ++i) {
        const double x = 10.0 * i, y = 10.0 * j;
        const double east = std::max(0.0, x - 320.0);
        xyz << 430000 + x << " " << 4515000 + y << " "
            << 1600 + 0.01 * x + 0.002 * east * east * (1 + 0.3 * std::sin(y / 23)) << "\n";
      }
  }
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(runTinsmith("tin --points " + (dir / "site.xyz").string() + " --crs EPSG:26912 -q -o " +
                        tin.string())
                .exitCode,
            0);
  const std::string tile = "tile " + tin.string() + " --tolerance 0.2 --max-triangles 512 -q";
  ASSERT_EQ(runTinsmith(tile + " -o " + (dir / "one.3dtiles").string()).exitCode, 0);
  const auto one =
      nlohmann::json::parse(runTinsmith("info --json " + (dir / "one.3dtiles").string()).out);
  ASSERT_GE(one.at("finestZoom").get<int>(), 0);

  std::vector<std::string> shards{(dir / "top.3dtiles").string()};
  ASSERT_EQ(runTinsmith(tile + " --until-zoom 2 -o " + shards[0]).exitCode, 0);
  std::size_t subtreeTiles = 0;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const std::string id = "2/" + std::to_string(x) + "/" + std::to_string(y);
      shards.push_back((dir / ("s" + std::to_string(4 * y + x) + ".3dtiles")).string());
      const auto r =
          runTinsmith(tile + " --subtree " + id + " --unchecked-ancestors -o " + shards.back());
      ASSERT_EQ(r.exitCode, 0) << id << ": " << r.err;
      subtreeTiles += nlohmann::json::parse(runTinsmith("info --json " + shards.back()).out)
                          .at("tiles")
                          .get<std::size_t>();
    }
  std::size_t oneBelow = 0;  // the single run's tiles at zoom 2 and deeper
  for (const auto& z : one.at("zooms"))
    if (z.at("zoom").get<int>() >= 2) oneBelow += z.at("tiles").get<std::size_t>();
  EXPECT_GT(subtreeTiles, oneBelow);  // the shards hold subtrees one run never built

  std::string all;
  for (const auto& s : shards) all += " " + s;
  auto r = runTinsmith("merge" + all + " -q -o " + (dir / "merged.3dtiles").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readFile(dir / "merged.3dtiles"), readFile(dir / "one.3dtiles"));

  // --unchecked-ancestors is for subtrees.
  EXPECT_EQ(
      runTinsmith(tile + " --unchecked-ancestors -o " + (dir / "u.3dtiles").string()).exitCode, 2);
}

TEST(SlurmCli, MergeRefusesAnUnfinishedShardAndAJobWithoutItsTop) {
  const fs::path dir = scratchDir("slurm-merge-refusals");
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=61&ny=61&spacing=10&noise=0.5").exitCode, 0);
  const std::string tile = "tile " + tin.string() + " --tolerance 0.2 --max-triangles 512 -q";
  ASSERT_EQ(runTinsmith(tile + " -o " + (dir / "one.3dtiles").string()).exitCode, 0);
  std::vector<fs::path> shards{dir / "0.3dtiles"};
  ASSERT_EQ(runTinsmith(tile + " --until-zoom 1 -o " + shards[0].string()).exitCode, 0);
  for (int k = 0; k < 4; ++k) {
    shards.push_back(dir / (std::to_string(k + 1) + ".3dtiles"));
    const std::string id = "1/" + std::to_string(k % 2) + "/" + std::to_string(k / 2);
    ASSERT_EQ(runTinsmith(tile + " --subtree " + id + " --unchecked-ancestors -o " +
                          shards.back().string())
                  .exitCode,
              0);
  }
  const auto merge = [&](const std::vector<fs::path>& inputs) {
    std::string all;
    for (const auto& s : inputs) all += " " + s.string();
    return runTinsmith("merge" + all + " -q -o " + (dir / "merged.3dtiles").string());
  };
  // A killed shard's stage: its record, some tiles, no mark of a finish
  // (made here from the finished store less the mark, as the stage was).
  const fs::path stage = dir / "2.partial.3dtiles";
  {
    const auto finished = store::openStoreForReading(shards[2]);
    std::vector<std::string> keys;
    for (const auto& key : finished->keys())
      if (key != "tinsmith/shard-finished.json") keys.push_back(key);
    ASSERT_LT(keys.size(), finished->keys().size());
    store::writeStore(*finished, keys, stage);
  }
  auto r = merge({shards[0], shards[1], stage, shards[3], shards[4]});
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("did not finish"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2.partial.3dtiles"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "merged.3dtiles"));
  // A finished shard that lost a tile.
  const fs::path lost = dir / "lost.3dtiles";
  {
    const auto finished = store::openStoreForReading(shards[2]);
    std::vector<std::string> keys;
    bool dropped = false;
    for (const auto& key : finished->keys()) {
      if (!dropped && key.rfind("tiles/", 0) == 0) {
        dropped = true;
        continue;
      }
      keys.push_back(key);
    }
    ASSERT_TRUE(dropped);
    store::writeStore(*finished, keys, lost);
  }
  r = merge({shards[0], shards[1], lost, shards[3], shards[4]});
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("tiles its shard finished with"), std::string::npos) << r.err;
  // A finished shard whose tile lost a bit on the way (a shared
  // filesystem's damage): its tile is named, and nothing is written.
  const fs::path flipped = dir / "flipped.3dtiles";
  fs::copy_file(shards[3], flipped);
  std::string damagedKey;
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open_v2(flipped.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
    sqlite3_stmt* read = nullptr;
    sqlite3_prepare_v2(db,
                       "SELECT key, content FROM media WHERE key LIKE 'tiles/%' ORDER BY key "
                       "LIMIT 1",
                       -1, &read, nullptr);
    ASSERT_EQ(sqlite3_step(read), SQLITE_ROW);
    damagedKey = reinterpret_cast<const char*>(sqlite3_column_text(read, 0));
    std::string bytes(static_cast<const char*>(sqlite3_column_blob(read, 1)),
                      static_cast<std::size_t>(sqlite3_column_bytes(read, 1)));
    sqlite3_finalize(read);
    bytes[bytes.size() / 2] ^= 0x10;
    sqlite3_stmt* write = nullptr;
    sqlite3_prepare_v2(db, "UPDATE media SET content = ? WHERE key = ?", -1, &write, nullptr);
    sqlite3_bind_blob(write, 1, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT);
    sqlite3_bind_text(write, 2, damagedKey.c_str(), -1, SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(write), SQLITE_DONE);
    sqlite3_finalize(write);
    sqlite3_close_v2(db);
  }
  r = merge({shards[0], shards[1], shards[2], flipped, shards[4]});
  EXPECT_EQ(r.exitCode, 3) << r.err;
  EXPECT_NE(r.err.find("flipped.3dtiles: its tile " + damagedKey + " is damaged"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("--resume --submit reruns it"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "merged.3dtiles"));
  // What tinsmith slurm --resume reruns (the tiles' bytes checked): every
  // one of these but the intact shard; the flipped tile goes unseen by the
  // check of keys alone.
  EXPECT_TRUE(ingest::isFinishedShard(shards[3], true));
  EXPECT_TRUE(ingest::isFinishedShard(flipped, false));
  for (const auto& rerun : {flipped, lost, stage, dir / "gone.3dtiles"})
    EXPECT_FALSE(ingest::isFinishedShard(rerun, true)) << rerun;
  // Its tinsmith tile command with --resume builds the flipped tile again
  // rather than carry it on under a new CRC: the shard's own bytes.
  ASSERT_EQ(
      runTinsmith(tile + " --subtree 1/0/1 --unchecked-ancestors --resume -o " + flipped.string())
          .exitCode,
      0);
  EXPECT_EQ(readFile(flipped), readFile(shards[3]));
  // The subtrees without the top, or one alone: no pyramid's root.
  for (const auto& inputs : {std::vector<fs::path>(shards.begin() + 1, shards.end()),
                             std::vector<fs::path>{shards[1]}}) {
    r = merge(inputs);
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_NE(r.err.find("none of the stores is the top of the pyramid"), std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(dir / "merged.3dtiles"));
  }
  // The finished shards: one run's bytes.
  r = merge(shards);
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readFile(dir / "merged.3dtiles"), readFile(dir / "one.3dtiles"));
}

TEST(SlurmCli, StrictEndsTheMergeWithExitOneWhenATileMissesItsTolerance) {
  // 64 triangles a tile cannot hold the hill within 5 cm: tiles miss their
  // zoom's tolerance. The shards do not fail for it (the merge runs after
  // them); with --strict the merge writes the store, tells what it holds and
  // what the shards cost, and ends with exit code 1.
  const fs::path dir = scratchDir("slurm-cli-strict");
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=61&ny=61&spacing=10&noise=0.5").exitCode, 0);
  const std::string tight = " --tolerance 0.05 --max-triangles 64 -q";
  ASSERT_EQ(runTinsmith("tile " + tin.string() + tight + " -o " + (dir / "one.3dtiles").string())
                .exitCode,
            0);
  for (const bool strict : {false, true}) {
    SCOPED_TRACE(strict);
    const std::string name = strict ? "strict" : "lenient";
    const fs::path work = dir / name;
    const fs::path merged = dir / (name + ".3dtiles");
    const auto planned =
        runTinsmith("slurm " + tin.string() + tight + (strict ? " --strict" : "") +
                    " --shard-zoom 1 --workdir " + work.string() + " -o " + merged.string());
    ASSERT_EQ(planned.exitCode, 0) << planned.err;
    for (int k = 0; k < 5; ++k) {
      const auto task = runCommand("SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " +
                                   (work / "shard.sh").string());
      EXPECT_EQ(task.exitCode, 0) << "task " << k << ": " << task.err;
    }
    const auto merge = runCommand("bash " + (work / "merge.sh").string());
    EXPECT_EQ(merge.exitCode, strict ? 1 : 0) << merge.err;
    EXPECT_NE(merge.err.find("over their zoom's tolerance"), std::string::npos) << merge.err;
    EXPECT_NE(merge.out.find("  all: CPU "), std::string::npos) << merge.out;
    EXPECT_EQ(readFile(merged), readFile(dir / "one.3dtiles"));
    // merge --strict itself, on the same shards.
    std::string stores;
    for (int k = 0; k < 5; ++k)
      stores += " " + (work / "shards" / (std::to_string(k) + ".3dtiles")).string();
    const auto again = runTinsmith("merge" + stores + (strict ? " --strict" : "") + " -q -o " +
                                   (dir / (name + "-again.3dtiles")).string());
    EXPECT_EQ(again.exitCode, strict ? 1 : 0) << again.err;
    EXPECT_EQ(readFile(dir / (name + "-again.3dtiles")), readFile(dir / "one.3dtiles"));
  }
}

/// A folder of stand-ins for sbatch and squeue, first on PATH: sbatch
/// queues job 101, 102, … and fails on its call number `failAt` (the queue
/// refusing a job) with a message on stderr; squeue lists the ids written in
/// `queue`. Slurm itself cannot be made to fail half way on purpose.
struct FailingSbatch {
  fs::path bin;
  FailingSbatch(const fs::path& dir, int failAt) : bin(dir / "bin") {
    fs::create_directories(bin);
    std::ofstream(bin / "sbatch") << "#!/bin/sh\n"
                                  << "n=$(cat '" << (bin / "calls").string()
                                  << "' 2>/dev/null || echo 0); n=$((n + 1))\n"
                                  << "echo $n > '" << (bin / "calls").string() << "'\n"
                                  << "if [ $n -eq " << failAt
                                  << " ]; then echo 'sbatch: error: QOSMaxSubmitJobPerUserLimit' "
                                     ">&2; exit 1; fi\n"
                                  << "echo $((100 + n))\n";
    std::ofstream(bin / "squeue") << "#!/bin/sh\ncat '" << (bin / "queue").string()
                                  << "' 2>/dev/null\n";
    std::ofstream(bin / "queue");
    for (const char* name : {"sbatch", "squeue"})
      fs::permissions(bin / name, fs::perms::owner_all, fs::perm_options::add);
  }
  [[nodiscard]] CommandResult run(const std::string& arguments) const {
    return runCommand("PATH='" + bin.string() + "':\"$PATH\" " + TINSMITH_BINARY + " " + arguments);
  }
  void queue(const std::string& ids) const { std::ofstream(bin / "queue") << ids; }
};

TEST(SlurmCli, ASubmissionThatFailsHalfWayIsRecordedAndResumedOnlyOnceItsJobsAreGone) {
  // tinsmith slurm (three sbatch calls: the top, the subtrees, the merge)
  // and slurm-tin (two: the blocks, the assembly), the second call failing:
  // the error names what was queued and how to cancel it, plan.json records
  // it, and --resume refuses while it is queued and submits once it is gone.
  const fs::path dir = scratchDir("slurm-cli-half-submitted");
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(makeHillTin(tin, "nx=41&ny=41&spacing=10").exitCode, 0);
  struct Job {
    std::string name, arguments, afterKey;
    std::vector<std::string> queued;  ///< the ids recorded before the failure
  };
  const std::vector<Job> jobs = {
      {"slurm",
       "slurm " + tin.string() + " --shard-zoom 1 -o " + (dir / "a.3dtiles").string(),
       "merge",
       {"top"}},
      {"slurm-tin",
       "slurm-tin --points 'synthetic:random?n=3000&seed=3&width=600&height=500&x0=431000"
       "&y0=4512000' --crs EPSG:26912 --block-points 1000 --max-circumradius 60 -o " +
           (dir / "b.tin").string(),
       "assemble",
       {"array"}}};
  for (const auto& job : jobs) {
    SCOPED_TRACE(job.name);
    const FailingSbatch sbatch(dir / job.name, 2);
    const fs::path work = dir / job.name / "work";
    const std::string args = job.arguments + " -q --workdir " + work.string() + " --submit";
    auto r = sbatch.run(args);
    EXPECT_EQ(r.exitCode, 5) << r.err;
    EXPECT_NE(r.err.find("QOSMaxSubmitJobPerUserLimit"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("scancel 101"), std::string::npos) << r.err;
    auto plan = nlohmann::json::parse(readFile(work / "plan.json"));
    ASSERT_EQ(plan.at("submissions").size(), 1u) << plan.dump(2);
    const auto& first = plan["submissions"][0];
    EXPECT_EQ(first.at(job.queued[0]).get<std::string>(), "101") << first;
    EXPECT_FALSE(first.contains(job.afterKey)) << first;
    // While job 101 is queued, --resume submits nothing.
    sbatch.queue("101\n");
    r = sbatch.run(args + " --resume");
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_NE(r.err.find("still queued or running: 101"), std::string::npos) << r.err;
    EXPECT_EQ(readFile(sbatch.bin / "calls"), "2\n");
    // Once it is gone (cancelled), --resume submits the job whole again:
    // nothing it queued ran.
    sbatch.queue("");
    r = sbatch.run(args + " --resume");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    plan = nlohmann::json::parse(readFile(work / "plan.json"));
    ASSERT_EQ(plan.at("submissions").size(), 2u) << plan.dump(2);
    EXPECT_EQ(plan["submissions"][1].at("tasks"), plan["submissions"][0].at("tasks"));
    EXPECT_TRUE(plan["submissions"][1].contains(job.afterKey)) << plan.dump(2);
  }
}

}  // namespace
}  // namespace tinsmith::test
