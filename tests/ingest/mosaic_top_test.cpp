// The top of the pyramid fitted to the mosaic of the mosaic zoom K's tiles
// (tiles::TilerOptions::mosaicPoints, tiles::buildPyramid) through the
// tiling job: one run, its shards at any zoom from K down merged into its
// bytes, a resumed run, shards above K refused, the tiles above K stored
// always and never built on demand. (Over 2^18 vertices a TIN gets K > 0;
// here the points per square are made small instead of the TIN large.)
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/tiles/tile_content.hpp"
#include "core/tiles/tileset_json.hpp"
#include "core/tin/hull_trim.hpp"
#include "ingest/base/progress.hpp"
#include "ingest/store/stored_tin.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tiles/tile_rebuild.hpp"
#include "ingest/tiles/tiling_plan.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"
#include "tests/support/test_terrain.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;
using tiles::TileId;

TinData rippledTin() {
  TinData tin = test::rippledRiverTin();
  tin.crs = "EPSG:26912";
  return tin;
}

/// The rippled hill's grid with its north-east quadrant nodata, its hull
/// trimmed: zoom 2's three tiles away from the notch's corner hold no
/// terrain, and the mosaic has a hole a quarter of the square.
TinData lShapedTin() {
  Cdt cdt;
  const FeatureId cells = cdt.addFeature(FeatureKind::SpotHeight, "dem");
  std::vector<Point3> points;
  for (int j = 0; j <= 80; ++j)
    for (int i = 0; i <= 80; ++i) {
      if (i > 40 && j > 40) continue;
      const double x = i * 12.5, y = j * 12.5;
      points.push_back(
          {500000 + x, 4500000 + y, test::hill(x, y) + 0.8 * std::sin(x / 37) * std::cos(y / 53)});
    }
  cdt.insertPoints(points, cells);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  EXPECT_GT(trimHull(tin, 3 * 12.5), 0u);
  tin.crs = "EPSG:26912";
  return tin;
}

TileJobOptions mosaicOptions() {
  TileJobOptions o;
  o.tiler.tolerance = 0.05;
  o.tiler.maxTriangles = 1024;
  o.tiler.mosaicPoints = 1024;  // 6 600 vertices: K = 2
  o.threads = 2;
  return o;
}

/// Every tile of a store by key.
std::map<std::string, std::string> tilesOf(const fs::path& path) {
  const auto store = store::openStoreForReading(path);
  std::map<std::string, std::string> tiles;
  for (const auto& key : store->keys())
    if (key.rfind("tiles/", 0) == 0) tiles[key] = *store->get(key);
  return tiles;
}

nlohmann::json buildOf(const fs::path& path) {
  return nlohmann::json::parse(*store::openStoreForReading(path)->get("tinsmith/build.json"));
}

/// The keys of a store that start with `prefix`.
std::vector<std::string> keysOf(const fs::path& path, const std::string& prefix) {
  std::vector<std::string> out;
  for (const auto& key : store::openStoreForReading(path)->keys())
    if (key.rfind(prefix, 0) == 0) out.push_back(key);
  return out;
}

/// The top of a sharded job (`--until-zoom shardZoom --write-plan`) and its
/// subtrees at shardZoom taking the plan, merged into `merged`; the stores
/// in the order they were made (the top first).
std::vector<fs::path> shardAndMerge(const TinData& tin, const std::string& name,
                                    const fs::path& dir, int shardZoom, const fs::path& merged) {
  const TileJobOptions options = mosaicOptions();
  std::vector<fs::path> shards{dir / "top.3dtiles"};
  TileJobOptions top = options;
  top.untilZoom = shardZoom;
  top.writePlan = dir / "tiler.plan";
  runTileJob(tin, name, shards[0], top);
  // No shard holds a tile above K = 2: the merge builds them, from the
  // surfaces of zoom 2's tiles, which the shards that hold those tiles
  // hand over (the top, when it goes below K).
  for (const auto& key : keysOf(shards[0], "tiles/")) EXPECT_GE(key[6] - '0', 2) << key;
  EXPECT_EQ(keysOf(shards[0], "tinsmith/surfaces/").size(),
            shardZoom > 2 ? keysOf(shards[0], "tiles/2/").size() : 0u);
  const auto plan = std::make_shared<const TilingPlan>(readTilingPlan(dir / "tiler.plan"));
  const std::uint32_t side = 1U << shardZoom;
  for (std::uint32_t y = 0; y < side; ++y)
    for (std::uint32_t x = 0; x < side; ++x) {
      TileJobOptions subtree = options;
      subtree.subtree = TileId{shardZoom, x, y};
      subtree.uncheckedAncestors = true;
      subtree.plan = plan;
      shards.push_back(dir /
                       ("subtree-" + std::to_string(x) + "-" + std::to_string(y) + ".3dtiles"));
      runTileJob(tin, name, shards.back(), subtree);
      const auto held = keysOf(shards.back(), "tinsmith/surfaces/");
      if (shardZoom == 2 && !keysOf(shards.back(), "tiles/").empty()) {
        EXPECT_EQ(held, std::vector<std::string>{"tinsmith/surfaces/2/" + std::to_string(x) + "/" +
                                                 std::to_string(y)});
      } else {
        EXPECT_TRUE(held.empty());
      }
    }
  // The merge's progress goes through the zooms it builds.
  std::set<std::string> built;
  Progress progress{[&](std::string_view stage, std::string_view detail, std::uint64_t done,
                        std::uint64_t total) {
    if (stage == "tiles.zoom" && done == total) built.emplace(detail);
  }};
  const TileJobSummary summary = mergeTileStores(shards, merged, 2, &progress);
  EXPECT_EQ(built, (std::set<std::string>{"zoom 0", "zoom 1"}));
  const auto above = keysOf(merged, "tiles/0/").size() + keysOf(merged, "tiles/1/").size();
  EXPECT_EQ(summary.built, above);
  EXPECT_EQ(summary.built + summary.reused, keysOf(merged, "tiles/").size());
  return shards;
}

TEST(MosaicTop, OneRunsTopIsFittedToZoomKsMosaicAndItsShardsMergeIntoItsBytes) {
  const fs::path dir = test::scratchDir("mosaic-top");
  const TinData tin = rippledTin();
  runTileJob(tin, "ripple.tin", dir / "one.3dtiles", mosaicOptions());
  const nlohmann::json build = buildOf(dir / "one.3dtiles");
  ASSERT_EQ(build["pyramid"]["mosaicZoom"], 2);
  ASSERT_GE(build["pyramid"]["finestZoom"].get<int>(), 3);
  const auto one = tilesOf(dir / "one.3dtiles");
  // Every tile above K with terrain refines: all of zoom 1 and 2 are there.
  for (std::uint32_t y = 0; y < 4; ++y)
    for (std::uint32_t x = 0; x < 4; ++x) {
      EXPECT_TRUE(one.contains(tiles::tileContentKey({2, x, y}))) << x << " " << y;
      EXPECT_TRUE(one.contains(tiles::tileContentKey({1, x / 2, y / 2})));
    }
  const auto below = std::count_if(
      one.begin(), one.end(), [](const auto& kv) { return kv.first.rfind("tiles/3/", 0) == 0; });
  EXPECT_GT(below, 0);

  // A tile above K declares its error against the mosaic plus the largest
  // of its zoom-K tiles': at least that.
  double largestK = 0;
  for (const auto& [key, bytes] : one)
    if (key.rfind("tiles/2/", 0) == 0)
      largestK = std::max(largestK, tiles::recordFromGlb(bytes)->error);
  ASSERT_GT(largestK, 0);
  EXPECT_GE(tiles::recordFromGlb(one.at(tiles::tileContentKey({})))->error, largestK);

  // Without a mosaic (mosaicPoints 0) zoom K and below are the same bytes,
  // the top is not; on one thread, the same bytes as on two.
  TileJobOptions plain = mosaicOptions();
  plain.tiler.mosaicPoints = 0;
  runTileJob(tin, "ripple.tin", dir / "plain.3dtiles", plain);
  EXPECT_EQ(buildOf(dir / "plain.3dtiles")["pyramid"]["mosaicZoom"], 0);
  for (const auto& [key, bytes] : tilesOf(dir / "plain.3dtiles")) {
    const int z = key[6] - '0';
    if (z < 2) {
      EXPECT_NE(bytes, one.at(key)) << key;
    } else if (one.contains(key)) {
      EXPECT_EQ(bytes, one.at(key)) << key;
    }
  }
  TileJobOptions single = mosaicOptions();
  single.threads = 1;
  runTileJob(tin, "ripple.tin", dir / "single.3dtiles", single);
  EXPECT_EQ(test::readFile(dir / "single.3dtiles"), test::readFile(dir / "one.3dtiles"));

  // The shards at the mosaic zoom and below it, merged: the one run's bytes.
  for (const int shardZoom : {2, 3}) {
    SCOPED_TRACE("shard zoom " + std::to_string(shardZoom));
    const fs::path shards = dir / ("shards-" + std::to_string(shardZoom));
    fs::create_directories(shards);
    shardAndMerge(tin, "ripple.tin", shards, shardZoom, shards / "merged.3dtiles");
    EXPECT_EQ(test::readFile(shards / "merged.3dtiles"), test::readFile(dir / "one.3dtiles"));
  }

  // Resumed over itself, every tile reused: zoom K's surfaces are built
  // again for the mosaic, and nothing changes.
  fs::copy_file(dir / "one.3dtiles", dir / "resumed.3dtiles");
  TileJobOptions resume = mosaicOptions();
  resume.resume = true;
  const TileJobSummary again = runTileJob(tin, "ripple.tin", dir / "resumed.3dtiles", resume);
  EXPECT_EQ(again.built, 0u);
  EXPECT_EQ(test::readFile(dir / "resumed.3dtiles"), test::readFile(dir / "one.3dtiles"));
  // A run that lost its top and some of zoom K (a folder store, their files
  // gone): resumed, the same tiles.
  runTileJob(tin, "ripple.tin", dir / "folder", mosaicOptions());
  for (const char* lost : {"tiles/0/0/0.glb", "tiles/1/1/0.glb", "tiles/2/0/0.glb"})
    ASSERT_TRUE(fs::remove(dir / "folder" / lost)) << lost;
  const TileJobSummary mended = runTileJob(tin, "ripple.tin", dir / "folder", resume);
  EXPECT_EQ(mended.built, 3u);
  EXPECT_EQ(tilesOf(dir / "folder"), one);
}

TEST(MosaicTop, ATinWithAnEmptyQuadrantHasATopWithAHoleAndItsShardsMergeIntoOneRunsBytes) {
  const fs::path dir = test::scratchDir("mosaic-top-l");
  const TinData tin = lShapedTin();
  runTileJob(tin, "l.tin", dir / "one.3dtiles", mosaicOptions());
  ASSERT_EQ(buildOf(dir / "one.3dtiles")["pyramid"]["mosaicZoom"], 2);
  const auto one = tilesOf(dir / "one.3dtiles");
  EXPECT_TRUE(one.contains(tiles::tileContentKey({})));
  EXPECT_TRUE(one.contains(tiles::tileContentKey({1, 0, 1})));
  EXPECT_TRUE(one.contains(tiles::tileContentKey({2, 1, 1})));
  for (const TileId id : {TileId{2, 3, 2}, TileId{2, 2, 3}, TileId{2, 3, 3}})
    EXPECT_FALSE(one.contains(tiles::tileContentKey(id))) << id.name();
  shardAndMerge(tin, "l.tin", dir, 2, dir / "merged.3dtiles");
  EXPECT_EQ(test::readFile(dir / "merged.3dtiles"), test::readFile(dir / "one.3dtiles"));
}

/// The message of the Error `run` throws ("" when it throws none).
template <class Run>
std::string errorOf(const Run& run) {
  try {
    run();
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

TEST(MosaicTop, TheMergeNamesAShardThatLacksItsZoomKSurfaceOrDamagedIt) {
  const fs::path dir = test::scratchDir("mosaic-top-surfaces");
  const TinData tin = rippledTin();
  std::vector<fs::path> shards = shardAndMerge(tin, "ripple.tin", dir, 2, dir / "merged.3dtiles");
  const fs::path merged = dir / "again.3dtiles";
  const std::string key = "tinsmith/surfaces/2/0/0";
  const fs::path& shard00 = shards[1];  // subtree 2/0/0
  ASSERT_EQ(shard00.filename(), "subtree-0-0.3dtiles");

  // A resumed shard takes its tile and surface back, built again by nothing.
  TileJobOptions subtree = mosaicOptions();
  subtree.subtree = TileId{2, 0, 0};
  subtree.uncheckedAncestors = true;
  subtree.plan = std::make_shared<const TilingPlan>(readTilingPlan(dir / "tiler.plan"));
  subtree.resume = true;
  const std::string before = test::readFile(shard00);
  EXPECT_EQ(runTileJob(tin, "ripple.tin", shard00, subtree).built, 0u);
  EXPECT_EQ(test::readFile(shard00), before);

  // Without the shard of a zoom-2 tile the top cannot be built.
  std::vector<fs::path> without = shards;
  without.erase(without.begin() + 1);
  std::string what = errorOf([&] { mergeTileStores(without, merged); });
  EXPECT_NE(what.find("tile 2/0/0, of the mosaic zoom 2"), std::string::npos) << what;
  EXPECT_NE(what.find("add the shard of subtree 2/0/0"), std::string::npos) << what;

  // Its surface damaged (the CRC-32 it finished with no longer holds).
  const auto copyOf = [&](const fs::path& to, const std::vector<std::string>& keys) {
    const auto from = store::openStoreForReading(shard00);
    store::writeStore(*from, keys, to);
    return store::openStoreForWriting(to, true);
  };
  const auto keysBut = [&](const std::string& left) {
    std::vector<std::string> keys;
    for (const auto& k : store::openStoreForReading(shard00)->keys())
      if (k != left) keys.push_back(k);
    return keys;
  };
  std::vector<fs::path> damaged = shards;
  damaged[1] = dir / "damaged.3dtiles";
  {
    auto st = copyOf(damaged[1], keysBut(""));
    std::string bytes = *st->get(key);
    bytes[bytes.size() / 2] ^= 1;
    st->put(key, bytes);
  }
  what = errorOf([&] { mergeTileStores(damaged, merged); });
  // tinsmith slurm --resume reruns it: read through, it is no finished shard.
  EXPECT_TRUE(isFinishedShard(shard00, true));
  EXPECT_TRUE(isFinishedShard(damaged[1], false));
  EXPECT_FALSE(isFinishedShard(damaged[1], true));
  EXPECT_NE(what.find("damaged.3dtiles"), std::string::npos) << what;
  EXPECT_NE(what.find(key + " is damaged"), std::string::npos) << what;

  // A shard as an older tinsmith wrote it: no surfaces, none listed.
  std::vector<fs::path> older = shards;
  older[1] = dir / "older.3dtiles";
  {
    auto st = copyOf(older[1], keysBut(key));
    auto finished = nlohmann::json::parse(*st->get("tinsmith/shard-finished.json"));
    finished.erase("surfaces");
    st->put("tinsmith/shard-finished.json", finished.dump());
  }
  what = errorOf([&] { mergeTileStores(older, merged); });
  EXPECT_NE(what.find("older.3dtiles"), std::string::npos) << what;
  EXPECT_NE(what.find("built by an older tinsmith"), std::string::npos) << what;
  EXPECT_FALSE(isFinishedShard(older[1], false));
  // Its surface gone but still listed: a shard that lost it.
  std::vector<fs::path> lost = shards;
  lost[1] = dir / "lost.3dtiles";
  (void)copyOf(lost[1], keysBut(key));
  what = errorOf([&] { mergeTileStores(lost, merged); });
  EXPECT_NE(what.find("holds 0 of the 1 tile surfaces its shard finished with"), std::string::npos)
      << what;
  EXPECT_FALSE(isFinishedShard(lost[1], false));
  EXPECT_FALSE(fs::exists(merged));
}

TEST(MosaicTop, ShardsAboveTheMosaicZoomAreRefusedBeforeAnythingIsWritten) {
  const fs::path dir = test::scratchDir("mosaic-top-refused");
  const TinData tin = rippledTin();
  TileJobOptions top = mosaicOptions();
  top.untilZoom = 1;
  top.writePlan = dir / "tiler.plan";
  TileJobOptions subtree = mosaicOptions();
  subtree.subtree = TileId{1, 1, 0};
  for (const auto& [options, name] :
       {std::pair{top, "--until-zoom 1"}, {subtree, "subtree 1/1/0"}}) {
    try {
      runTileJob(tin, "ripple.tin", dir / "above.3dtiles", options);
      ADD_FAILURE() << name << " was tiled";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(name), std::string::npos) << what;
      EXPECT_NE(what.find("above zoom 2"), std::string::npos) << what;
      EXPECT_NE(what.find("--shard-zoom 2 or more"), std::string::npos) << what;
    }
  }
  // Nothing written: no store, no stage, no plan.
  EXPECT_TRUE(fs::is_empty(dir)) << fs::directory_iterator(dir)->path();
  // A subtree at the mosaic zoom is in the pyramid with no tile above it
  // built: its ancestors above K refine as they hold terrain.
  subtree.subtree = TileId{2, 3, 1};
  runTileJob(tin, "ripple.tin", dir / "sub.3dtiles", subtree);
  EXPECT_TRUE(tilesOf(dir / "sub.3dtiles").contains(tiles::tileContentKey({2, 3, 1})));
}

TEST(MosaicTop, TheTilesAboveTheMosaicZoomAreAlwaysStoredAndNeverBuiltOnDemand) {
  const fs::path dir = test::scratchDir("mosaic-top-stored");
  const TinData tin = rippledTin();
  TileJobOptions options = mosaicOptions();
  options.storeUntilZoom = 1;
  runTileJob(tin, "ripple.tin", dir / "lean.3dtiles", options);
  const auto lean = tilesOf(dir / "lean.3dtiles");
  EXPECT_TRUE(lean.contains(tiles::tileContentKey({1, 0, 0})));
  EXPECT_TRUE(lean.contains(tiles::tileContentKey({1, 1, 1})));
  EXPECT_FALSE(lean.contains(tiles::tileContentKey({2, 0, 0})));

  const auto store = store::openStoreForReading(dir / "lean.3dtiles");
  const TileRebuilder rebuilder(*store->get("tinsmith/build.json"), *store::getTin(*store),
                                "lean.3dtiles");
  EXPECT_THROW((void)rebuilder.build({1, 0, 0}), Error);
  // Below it a tile is the TIN's alone: built on demand, it is the one a
  // whole run stores.
  runTileJob(tin, "ripple.tin", dir / "one.3dtiles", mosaicOptions());
  const auto one = tilesOf(dir / "one.3dtiles");
  for (const TileId id : {TileId{2, 0, 0}, TileId{2, 3, 2}}) {
    const auto built = rebuilder.build(id);
    ASSERT_TRUE(built) << id.name();
    EXPECT_EQ(built->glb, one.at(tiles::tileContentKey(id))) << id.name();
  }
}

}  // namespace
}  // namespace tinsmith::ingest
