// tinsmith tile / merge / info on a store: a small TIN from synthetic points,
// tiled into an archive; the same bytes for any thread count, for a resumed
// run and for shards merged; bad input fails clearly and leaves no store.
#include <gtest/gtest.h>

#include <fstream>

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
  for (const char* name : {"a.3dtiles", "b.3dtiles", "c.3dtiles", "d.3dtiles"}) {
    EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
  }
}

}  // namespace
}  // namespace tinsmith::test
