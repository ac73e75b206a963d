#include "core/tiles/geographic_grid.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/base/error.hpp"

namespace tinsmith::tiles {

bool isGeographicTile(const TileId& id) {
  return id.z >= 0 && id.z <= 30 && id.x < (std::uint64_t{2} << id.z) &&
         id.y < (std::uint64_t{1} << id.z);
}

GeoRect geographicTileBounds(const TileId& id) {
  if (!isGeographicTile(id))
    throw usageError("tile " + id.name() + " is not a tile of the geographic (TMS) grid");
  const double side = std::ldexp(180.0, -id.z);
  return {-180.0 + side * id.x, -90.0 + side * id.y, -180.0 + side * (id.x + 1.0),
          -90.0 + side * (id.y + 1.0)};
}

double cesiumLevelMaximumGeometricError(int level) {
  constexpr double kWgs84A = 6378137.0;
  return std::ldexp(kWgs84A * 2 * std::numbers::pi * 0.25 / (65.0 * 2.0), -level);
}

std::optional<TileRange> geographicTilesCovering(const GeoRect& rect, int level) {
  if (level < 0 || level > 30) return std::nullopt;
  const double west = std::max(rect.west, -180.0), east = std::min(rect.east, 180.0);
  const double south = std::max(rect.south, -90.0), north = std::min(rect.north, 90.0);
  if (!(west <= east && south <= north)) return std::nullopt;
  const double side = std::ldexp(180.0, -level);
  const auto columns = static_cast<double>(std::uint64_t{2} << level);
  const auto rows = static_cast<double>(std::uint64_t{1} << level);
  auto cell = [&](double offset, double count) {
    return static_cast<std::uint32_t>(std::clamp(std::floor(offset / side), 0.0, count - 1));
  };
  TileRange r;
  r.startX = cell(west + 180.0, columns);
  r.endX = cell(east + 180.0, columns);
  r.startY = cell(south + 90.0, rows);
  r.endY = cell(north + 90.0, rows);
  return r;
}

}  // namespace tinsmith::tiles
