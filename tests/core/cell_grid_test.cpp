// CellGrid (core/geometry/cell_grid.hpp): the grid walk along a segment.
#include "core/geometry/cell_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace tinsmith {
namespace {

/// The cells (i, j) whose open squares the segment a → b passes through,
/// by dense sampling (the walk must visit every cell the segment's interior
/// crosses; grazing a corner exactly is not asked of it).
std::set<std::pair<std::int64_t, std::int64_t>> crossedCells(double x0, double y0, double cell,
                                                             double ax, double ay, double bx,
                                                             double by) {
  std::set<std::pair<std::int64_t, std::int64_t>> cells;
  for (int k = 0; k <= 20000; ++k) {
    const double t = k / 20000.0;
    const double x = ax + t * (bx - ax), y = ay + t * (by - ay);
    cells.insert({static_cast<std::int64_t>(std::floor((x - x0) / cell)),
                  static_cast<std::int64_t>(std::floor((y - y0) / cell))});
  }
  return cells;
}

TEST(CellGrid, TheSegmentWalkVisitsEveryCellTheSegmentCrossesOnce) {
  // UTM-sized origin, cells of 37.5 m.
  const double x0 = 500000, y0 = 4500000;
  const CellGrid grid(x0, y0, x0 + 1500, y0 + 1200, 37.5);  // 41 × 33 cells
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ux(x0 - 100, x0 + 1600), uy(y0 - 100, y0 + 1300);
  for (int trial = 0; trial < 300; ++trial) {
    double ax = ux(rng), ay = uy(rng), bx = ux(rng), by = uy(rng);
    if (trial % 10 == 0) by = ay;              // horizontal
    if (trial % 10 == 1) bx = ax;              // vertical
    if (trial % 10 == 2) bx = ax + (by - ay);  // diagonal through grid corners
    if (trial % 10 == 3) bx = ax, by = ay;     // a point
    std::vector<std::size_t> visited;
    grid.forEachCellOfSegment(ax, ay, bx, by, [&](std::size_t c) { visited.push_back(c); });
    const std::set<std::size_t> unique(visited.begin(), visited.end());
    EXPECT_EQ(unique.size(), visited.size()) << "trial " << trial << " visits a cell twice";
    for (const auto& [i, j] : crossedCells(x0, y0, 37.5, ax, ay, bx, by)) {
      if (i < 0 || j < 0 || i >= 41 || j >= 33) continue;  // outside the grid
      EXPECT_TRUE(unique.count(grid.index(i, j)))
          << "trial " << trial << " misses cell " << i << ", " << j;
    }
  }
}

}  // namespace
}  // namespace tinsmith
