// Synthetic terrain the tests of more than one module tile.
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include "core/cdt/cdt.hpp"

namespace tinsmith::test {

/// A smooth hill 30 m high over a 100 m plain, its top at (400, 600).
inline double hill(double x, double y) {
  return 100 + 30 * std::exp(-((x - 400) * (x - 400) + (y - 600) * (y - 600)) / 6e4);
}

/// A 1 km square of 81 × 81 points on a rippled hill with a river across
/// it, a road beside it and a square hole, at UTM-sized coordinates:
/// detail enough for tiles down to zoom 2 and more within a tile's budget.
inline TinData rippledRiverTin() {
  Cdt cdt;
  const FeatureId spots = cdt.addFeature(FeatureKind::SpotHeight, "spots");
  const FeatureId river = cdt.addFeature(FeatureKind::River, "river");
  const FeatureId road = cdt.addFeature(FeatureKind::Road, "road");
  const FeatureId hole = cdt.addFeature(FeatureKind::Hole, "hole");
  const double x0 = 500000, y0 = 4500000;
  const auto z = [](double x, double y) {
    return hill(x, y) + 0.8 * std::sin(x / 37) * std::cos(y / 53);
  };
  std::vector<Point3> points;
  for (int j = 0; j <= 80; ++j)
    for (int i = 0; i <= 80; ++i)
      points.push_back({x0 + i * 12.5, y0 + j * 12.5, z(i * 12.5, j * 12.5)});
  cdt.insertPoints(points, spots);
  std::vector<Point3> line;
  for (int k = 0; k <= 30; ++k) {
    const double x = 20 + k * 31.0, y = 900 - k * 27.0 + 15 * std::sin(0.7 * k);
    line.push_back({x0 + x, y0 + y, z(x, y) - 1.0 - 0.01 * k});
  }
  cdt.insertConstraint(line, river);
  line.clear();
  for (int k = 0; k <= 6; ++k) {
    const double x = 50 + k * 50.0, y = 505 + 20 * std::sin(0.4 * k);
    line.push_back({x0 + x, y0 + y, z(x, y) + 0.3});
  }
  cdt.insertConstraint(line, road);
  std::vector<Point3> ring;
  for (const auto& [x, y] :
       {std::pair{120.0, 120.0}, {200.0, 120.0}, {200.0, 200.0}, {120.0, 200.0}})
    ring.push_back({x0 + x, y0 + y, z(x, y)});
  cdt.addHole(ring, hole);
  cdt.finalize();
  return cdt.toTinData();
}

}  // namespace tinsmith::test
