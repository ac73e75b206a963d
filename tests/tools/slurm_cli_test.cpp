// `tinsmith slurm` without a cluster: the scripts it writes run as Slurm
// would run them (each array task with its SLURM_ARRAY_TASK_ID, then the
// merge), and the merged store has the bytes of one `tinsmith tile` run —
// also where subtrees hold no terrain (their tasks leave empty markers). Its
// work folder is refused when it holds something else or another job's plan.
// The same job on a real one-node Slurm cluster: tests/slurm.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/run_command.hpp"

namespace tinsmith::test {
namespace {

namespace fs = std::filesystem;

/// Runs every task of `workdir`'s shard.sh, then its merge.sh, as Slurm would.
void runAsSlurmWould(const fs::path& workdir, int tasks) {
  for (int k = 0; k < tasks; ++k) {
    const auto r = runCommand(
        "SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " + (workdir / "shard.sh").string() +
        " >" + (workdir / "logs" / ("shard-" + std::to_string(k) + ".log")).string() + " 2>&1");
    EXPECT_EQ(r.exitCode, 0) << "task " << k << ": "
                             << readFile(workdir / "logs" /
                                         ("shard-" + std::to_string(k) + ".log"));
  }
  const auto merge = runCommand("bash " + (workdir / "merge.sh").string() + " >" +
                                (workdir / "logs" / "merge.log").string() + " 2>&1");
  EXPECT_EQ(merge.exitCode, 0) << readFile(workdir / "logs" / "merge.log");
}

TEST(SlurmCli, TheScriptsShardAndMergeIntoTheBytesOfOneRun) {
  const fs::path dir = scratchDir("slurm-cli");
  // 1.2 km × 0.4 km: the square's north half holds no terrain, so 8 of the
  // 16 subtrees at zoom 2 are not in the pyramid.
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(runTinsmith("tin --points 'synthetic:grid?nx=121&ny=41&spacing=10&x0=430000&y0=4515000"
                        "&surface=hill&z0=1600&scale=80&noise=0.5' --crs EPSG:26912 -q -o " +
                        tin.string())
                .exitCode,
            0);
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
  EXPECT_NE(out.at("commands")[0].get<std::string>().find("sbatch --parsable --array=0-16"),
            std::string::npos);
  EXPECT_NE(out.at("commands")[1].get<std::string>().find("afterok:ARRAY_ID_0:ARRAY_ID_1"),
            std::string::npos);
  runAsSlurmWould(work, 17);
  EXPECT_EQ(readFile(dir / "merged.3dtiles"), readFile(dir / "one.3dtiles"));
  int empty = 0;
  for (const auto& e : fs::directory_iterator(work / "shards"))
    empty += e.path().extension() == ".empty";
  EXPECT_EQ(empty, 8);

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

TEST(SlurmCli, ASubtreeOutsideThePyramidIsAnErrorUnlessEmptyIsOk) {
  const fs::path dir = scratchDir("slurm-empty-ok");
  const fs::path tin = dir / "site.tin";
  ASSERT_EQ(runTinsmith("tin --points 'synthetic:grid?nx=121&ny=41&spacing=10&x0=430000"
                        "&y0=4515000&surface=hill&z0=1600&scale=80' --crs EPSG:26912 -q -o " +
                        tin.string())
                .exitCode,
            0);
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

}  // namespace
}  // namespace tinsmith::test
