// The TIN a tile store carries, in pieces when it is larger than one
// (ingest/store/stored_tin.hpp), through the tiling job: a run writes the
// pieces, merged shards copy them into the bytes of the one run, and the
// rebuilder (the server's tiles on demand) takes the TIN joined from them.
// (An archive's value holds at most 10⁹ bytes; here the pieces are made
// small instead of the TIN large.)
#include "ingest/store/stored_tin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/tiles/tileset_json.hpp"
#include "ingest/store/tile_store.hpp"
#include "ingest/tiles/tile_job.hpp"
#include "ingest/tiles/tile_rebuild.hpp"
#include "ingest/tinfile/tin_file.hpp"
#include "tests/support/run_command.hpp"

namespace tinsmith::ingest {
namespace {

namespace fs = std::filesystem;

/// 1.2 km × 900 m of a rolling hill, a point every 30 m (rows shifted by
/// half a step), at UTM-sized coordinates in NAD83 / UTM 12N.
TinData rollingHill() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  std::vector<Point3> points;
  for (int row = 0; row <= 30; ++row) {
    for (int column = 0; column <= 40; ++column) {
      const double x = column * 30.0 + (row % 2 ? 15.0 : 0.0), y = row * 30.0;
      points.push_back(
          {431000 + x, 4512000 + y, 1500 + 25 * std::sin(x / 190) + 18 * std::cos(y / 140)});
    }
  }
  cdt.insertPoints(points, spots);
  cdt.finalize();
  TinData tin = cdt.toTinData();
  tin.crs = "EPSG:26912";
  return tin;
}

TEST(StoredTin, ARunAndItsMergedShardsKeepATinLargerThanAPieceInPieces) {
  const fs::path dir = test::scratchDir("stored-tin");
  const TinData tin = rollingHill();
  const std::string bytes = encodeTin(tin);
  TileJobOptions options;
  options.tiler.tolerance = 0.5;
  options.tiler.maxTriangles = 256;
  options.threads = 1;
  options.tinPieceBytes = bytes.size() / 4 + 1;  // four pieces
  runTileJob(tin, "hill.tin", dir / "one.3dtiles", options);
  const auto one = store::openStoreForReading(dir / "one.3dtiles");
  EXPECT_FALSE(one->contains(store::kTinKey));
  EXPECT_EQ(store::storedTinKeys(*one).size(), 4u);
  ASSERT_EQ(store::getTin(*one), bytes);

  // The top above zoom 1 (it carries the TIN) and the four subtrees at zoom
  // 1, merged: the one run's bytes.
  std::vector<fs::path> shards{dir / "top.3dtiles"};
  TileJobOptions top = options;
  top.untilZoom = 1;
  runTileJob(tin, "hill.tin", shards[0], top);
  for (std::uint32_t k = 0; k < 4; ++k) {
    TileJobOptions subtree = options;
    subtree.subtree = tiles::TileId{1, k % 2, k / 2};
    subtree.uncheckedAncestors = true;
    shards.push_back(dir / ("subtree-" + std::to_string(k) + ".3dtiles"));
    runTileJob(tin, "hill.tin", shards.back(), subtree);
    EXPECT_FALSE(store::holdsTin(*store::openStoreForReading(shards.back()))) << k;
  }
  mergeTileStores(shards, dir / "merged.3dtiles");
  EXPECT_EQ(test::readFile(dir / "merged.3dtiles"), test::readFile(dir / "one.3dtiles"));

  // Tiles on demand from the joined TIN: the root as it is stored.
  const TileRebuilder rebuilder(*one->get(store::kStoreMarkerKey), *store::getTin(*one), "one");
  const auto root = rebuilder.build(tiles::TileId{});
  ASSERT_TRUE(root);
  EXPECT_EQ(root->glb, one->get(tiles::tileContentKey(tiles::TileId{})));
}

TEST(StoredTin, AnEmptyTinLeftByAnOlderTinsmithIsNeitherResumedNorMerged) {
  // An older archive stored a TIN over 10⁹ bytes as an empty value; a stage
  // or a shard holding one must not pass it on as the TIN.
  const fs::path dir = test::scratchDir("stored-tin-empty");
  const TinData tin = rollingHill();
  TileJobOptions options;
  options.tiler.tolerance = 0.5;
  options.threads = 1;
  runTileJob(tin, "hill.tin", dir / "one.3dtiles", options);
  const auto one = store::openStoreForReading(dir / "one.3dtiles");
  EXPECT_FALSE(store::holdsEmptyTin(*one));
  {
    auto stage = store::openStoreForWriting(dir / "two.partial.3dtiles", false);
    stage->put(store::kStoreMarkerKey, *one->get(store::kStoreMarkerKey));
    stage->put(store::kTinKey, "");
    EXPECT_TRUE(store::holdsEmptyTin(*stage));
    auto copy = store::openStoreForWriting(dir / "copy.3dtiles", false);
    try {
      store::copyTin(*stage, *copy);
      ADD_FAILURE() << "an empty TIN was copied";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Input);
      EXPECT_NE(std::string(e.what()).find("two.partial.3dtiles"), std::string::npos) << e.what();
    }
  }
  TileJobOptions resume = options;
  resume.resume = true;
  try {
    runTileJob(tin, "hill.tin", dir / "two.3dtiles", resume);
    ADD_FAILURE() << "a stage with an empty TIN was resumed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("empty TIN"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "two.3dtiles"));
}

}  // namespace
}  // namespace tinsmith::ingest
