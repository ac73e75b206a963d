// The geographic (TMS, EPSG:4326) tile grid of Cesium terrain
// (core/tiles/geographic_grid.hpp), against the layout the quantized-mesh
// text lists for levels 0 and 1 and CesiumJS's level errors.
#include "core/tiles/geographic_grid.hpp"

#include <gtest/gtest.h>

#include "core/base/error.hpp"

namespace tinsmith::tiles {
namespace {

void expectBounds(const TileId& id, double w, double s, double e, double n) {
  const GeoRect r = geographicTileBounds(id);
  EXPECT_EQ(r.west, w) << id.name();
  EXPECT_EQ(r.south, s) << id.name();
  EXPECT_EQ(r.east, e) << id.name();
  EXPECT_EQ(r.north, n) << id.name();
}

TEST(GeographicGrid, LevelsZeroAndOneAreTheFormatsTwoAndEightTiles) {
  expectBounds({0, 0, 0}, -180, -90, 0, 90);
  expectBounds({0, 1, 0}, 0, -90, 180, 90);
  expectBounds({1, 0, 0}, -180, -90, -90, 0);
  expectBounds({1, 3, 0}, 90, -90, 180, 0);
  expectBounds({1, 1, 1}, -90, 0, 0, 90);
  expectBounds({1, 2, 1}, 0, 0, 90, 90);
  EXPECT_FALSE(isGeographicTile({0, 2, 0}));
  EXPECT_FALSE(isGeographicTile({1, 0, 2}));
  EXPECT_TRUE(isGeographicTile({30, (2U << 30) - 1, (1U << 30) - 1}));
  EXPECT_THROW(geographicTileBounds({0, 0, 1}), Error);
}

TEST(GeographicGrid, NeighboursShareTheirSidesBitForBit) {
  for (int z : {3, 17, 29}) {
    const TileId a{z, 12345U % (2U << z), 777U % (1U << z)};
    const TileId east{z, a.x + 1, a.y}, north{z, a.x, a.y + 1};
    EXPECT_EQ(geographicTileBounds(a).east, geographicTileBounds(east).west);
    EXPECT_EQ(geographicTileBounds(a).north, geographicTileBounds(north).south);
    // A child's outer sides are its parent's.
    EXPECT_EQ(geographicTileBounds(a.child(0)).west, geographicTileBounds(a).west);
    EXPECT_EQ(geographicTileBounds(a.child(3)).north, geographicTileBounds(a).north);
  }
}

TEST(GeographicGrid, CesiumsLevelErrorIsAbout77067MetresHalvedEachLevel) {
  EXPECT_NEAR(cesiumLevelMaximumGeometricError(0), 77067.34, 0.01);
  EXPECT_DOUBLE_EQ(cesiumLevelMaximumGeometricError(10),
                   cesiumLevelMaximumGeometricError(0) / 1024);
}

TEST(GeographicGrid, TheTilesCoveringARegionAreItsAvailableRanges) {
  // Red Butte, about 111.86° W–111.80° W, 40.76° N–40.82° N, at level 12
  // (tiles of 0.0439°).
  const auto r = geographicTilesCovering({-111.86, 40.76, -111.80, 40.82}, 12);
  ASSERT_TRUE(r);
  const double side = 180.0 / 4096;
  EXPECT_EQ(r->startX, static_cast<std::uint32_t>((180 - 111.86) / side));
  EXPECT_EQ(r->endX, static_cast<std::uint32_t>((180 - 111.80) / side));
  EXPECT_EQ(r->startY, static_cast<std::uint32_t>((90 + 40.76) / side));
  EXPECT_EQ(r->endY, static_cast<std::uint32_t>((90 + 40.82) / side));
  for (std::uint32_t x = r->startX; x <= r->endX; ++x) {
    const GeoRect b = geographicTileBounds({12, x, r->startY});
    EXPECT_LE(b.west, -111.80);
    EXPECT_GE(b.east, -111.86);
  }
  // The whole globe at level 0 is both tiles; the east edge at 180° is the
  // last column, not one past it.
  const auto all = geographicTilesCovering({-180, -90, 180, 90}, 0);
  ASSERT_TRUE(all);
  EXPECT_EQ(all->startX, 0u);
  EXPECT_EQ(all->endX, 1u);
  EXPECT_EQ(all->endY, 0u);
  EXPECT_FALSE(geographicTilesCovering({10, 5, 9, 6}, 3));
}

}  // namespace
}  // namespace tinsmith::tiles
