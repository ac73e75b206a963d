// tinsmith tile / merge / info on a store: a small TIN from synthetic points,
// tiled into an archive; the same bytes for any thread count, for a resumed
// run and for shards merged; bad input fails clearly and leaves no store.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/support/run_command.hpp"

namespace tinsmith::test {
namespace {

/// A small hill of 31 × 31 spot heights, 25 m apart and slightly irregular,
/// at UTM 12N-sized coordinates: a quick TIN to tile.
std::filesystem::path smallTin(const std::filesystem::path& dir) {
  const auto tin = dir / "hill.tin";
  const auto r = runTinsmith(
      "tin --points 'synthetic:grid?nx=31&ny=31&spacing=25&jitter=0.05&x0=430000&y0=4515000"
      "&surface=hill&z0=1600&scale=80' --crs EPSG:26912 -q -o " +
      tin.string());
  EXPECT_EQ(r.exitCode, 0) << r.err;
  return tin;
}

TEST(TileCli, AnArchiveIsTheSameForAnyThreadCountResumedOrMerged) {
  const auto dir = scratchDir("tile-cli");
  const auto tin = smallTin(dir);
  const std::string common = "tile " + tin.string() + " --tolerance 0.5 --max-triangles 2048 -q ";
  auto one = runTinsmith(common + "--threads 1 -o " + (dir / "one.3dtiles").string());
  ASSERT_EQ(one.exitCode, 0) << one.err;
  auto two = runTinsmith(common + "--threads 2 -o " + (dir / "two.3dtiles").string());
  ASSERT_EQ(two.exitCode, 0) << two.err;
  const std::string bytes = readFile(dir / "one.3dtiles");
  ASSERT_GT(bytes.size(), 1000u);
  EXPECT_EQ(bytes, readFile(dir / "two.3dtiles"));
  EXPECT_FALSE(std::filesystem::exists(dir / "one.partial.3dtiles"));

  // info reads the archive back.
  auto info = runTinsmith("info --json " + (dir / "one.3dtiles").string());
  ASSERT_EQ(info.exitCode, 0) << info.err;
  EXPECT_NE(info.out.find("\"zooms\""), std::string::npos);

  // Shards: the tiles above zoom 1, and each zoom-1 subtree, merged.
  auto top = runTinsmith(common + "--until-zoom 1 -o " + (dir / "top.3dtiles").string());
  ASSERT_EQ(top.exitCode, 0) << top.err;
  std::string shards = (dir / "top.3dtiles").string();
  for (int k = 0; k < 4; ++k) {
    const std::string id = "1/" + std::to_string(k & 1) + "/" + std::to_string(k >> 1);
    const auto out = dir / ("part" + std::to_string(k) + ".3dtiles");
    auto part = runTinsmith(common + "--subtree " + id + " -o " + out.string());
    if (part.exitCode != 0)
      continue;  // a subtree that is not in the pyramid (the root met the tolerance)
    shards += " " + out.string();
  }
  auto merged = runTinsmith("merge -q " + shards + " -o " + (dir / "merged.3dtiles").string());
  ASSERT_EQ(merged.exitCode, 0) << merged.err;
  EXPECT_EQ(bytes, readFile(dir / "merged.3dtiles"));

  // Resume: a staging archive that holds only some tiles is completed.
  std::filesystem::copy_file(dir / "top.3dtiles", dir / "resumed.partial.3dtiles");
  auto resumed = runTinsmith(common + "--resume --json -o " + (dir / "resumed.3dtiles").string());
  ASSERT_EQ(resumed.exitCode, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("\"kept\": "), std::string::npos);
  EXPECT_EQ(resumed.out.find("\"kept\": 0,"), std::string::npos);
  EXPECT_EQ(bytes, readFile(dir / "resumed.3dtiles"));
}

TEST(TileCli, BadInputFailsClearlyAndLeavesNoStore) {
  const auto dir = scratchDir("tile-cli-bad");
  const auto tin = smallTin(dir);
  auto r =
      runTinsmith("tile " + tin.string() + " --tolerance 0 -o " + (dir / "a.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_NE(r.err.find("tolerance"), std::string::npos);
  r = runTinsmith("tile " + (dir / "missing.tin").string() + " -o " + (dir / "b.3dtiles").string());
  EXPECT_EQ(r.exitCode, 3) << r.err;
  {
    std::ofstream bad(dir / "bad.tin");
    bad << "not a tin";
  }
  r = runTinsmith("tile " + (dir / "bad.tin").string() + " -o " + (dir / "c.3dtiles").string());
  EXPECT_EQ(r.exitCode, 3) << r.err;
  r = runTinsmith("tile " + tin.string() + " --subtree 9/999/0 -o " + (dir / "d.3dtiles").string());
  EXPECT_EQ(r.exitCode, 2) << r.err;
  // A TIN built without --crs: what to do, from tile and from slurm (which
  // reads the CRS from the file's head, before it writes anything).
  const auto bare = dir / "bare.tin";
  r = runTinsmith(
      "tin --points 'synthetic:grid?nx=31&ny=31&spacing=25&surface=hill&z0=100&scale=20' -q -o " +
      bare.string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const std::vector<std::string> commands = {
      "tile " + bare.string() + " -o " + (dir / "e.3dtiles").string(),
      "slurm " + bare.string() + " --shard-zoom 1 --workdir " + (dir / "work").string() + " -o " +
          (dir / "f.3dtiles").string()};
  for (const auto& command : commands) {
    r = runTinsmith(command);
    EXPECT_EQ(r.exitCode, 3) << command << ": " << r.err;
    EXPECT_NE(r.err.find(bare.string() + ": the TIN has no CRS"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("--crs EPSG:"), std::string::npos) << r.err;
  }
  for (const char* name :
       {"a.3dtiles", "b.3dtiles", "c.3dtiles", "d.3dtiles", "e.3dtiles", "f.3dtiles", "work"}) {
    EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
  }
}

TEST(TileCli, TilesOverTheirZoomsToleranceAreSaidAndStrictFails) {
  const auto dir = scratchDir("tile-cli-missed");
  const auto tin = smallTin(dir);
  // 64 triangles a tile cannot hold the hill within 5 cm.
  const std::string tight = "tile " + tin.string() + " --tolerance 0.05 --max-triangles 64 ";
  auto r = runTinsmith(tight + "--json -o " + (dir / "a.3dtiles").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("WARNING"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("over their zoom's tolerance"), std::string::npos) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["withinTolerance"].get<bool>());
  ASSERT_FALSE(j["overTolerance"].empty());
  std::size_t counted = 0;
  for (const auto& z : j["zooms"]) counted += z["overTolerance"].get<std::size_t>();
  EXPECT_EQ(counted, j["overTolerance"].size());
  // Each over its tolerance; the worst is named in the warning.
  nlohmann::json worst;
  for (const auto& m : j["overTolerance"]) {
    EXPECT_GT(m["error"].get<double>(), m["tolerance"].get<double>()) << m;
    const auto ratio = [](const nlohmann::json& t) {
      return t["error"].get<double>() / t["tolerance"].get<double>();
    };
    if (worst.is_null() || ratio(m) > ratio(worst)) worst = m;
  }
  EXPECT_NE(r.err.find(worst["tile"].get<std::string>()), std::string::npos) << worst;
  // --strict: the same store, and exit code 1.
  r = runTinsmith(tight + "-q --strict -o " + (dir / "b.3dtiles").string());
  EXPECT_EQ(r.exitCode, 1) << r.err;
  EXPECT_NE(r.err.find("WARNING"), std::string::npos) << r.err;
  EXPECT_EQ(readFile(dir / "a.3dtiles"), readFile(dir / "b.3dtiles"));
  // Within tolerance: no warning, and --strict passes.
  r = runTinsmith("tile " + tin.string() +
                  " --tolerance 0.5 --max-triangles 2048 --strict --json -o " +
                  (dir / "c.3dtiles").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(r.err.find("WARNING"), std::string::npos) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["withinTolerance"].get<bool>());
  EXPECT_TRUE(j["overTolerance"].empty());
}

TEST(TileCli, TheSummaryTellsWhatTheProcessCost) {
  const auto dir = scratchDir("tile-cli-process");
  const auto tin = smallTin(dir);
  auto r = runTinsmith("tile " + tin.string() + " --tolerance 0.5 --json -o " +
                       (dir / "a.3dtiles").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["cpuSeconds"].get<double>(), 0.0);
  // The libraries alone take tens of MB; this small job well under a GB.
  EXPECT_GT(j["peakMemoryBytes"].get<double>(), 10e6);
  EXPECT_LT(j["peakMemoryBytes"].get<double>(), 1e9);
  r = runTinsmith("tile " + tin.string() + " --tolerance 0.5 -o " + (dir / "b.3dtiles").string());
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("  process: CPU "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" MB\n"), std::string::npos) << r.err;
  // A store described is not a process measured.
  r = runTinsmith("info " + (dir / "a.3dtiles").string() + " --json");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_FALSE(nlohmann::json::parse(r.out).contains("cpuSeconds")) << r.out;
}

}  // namespace
}  // namespace tinsmith::test
