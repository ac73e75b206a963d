// The table-driven Hilbert index against the textbook rotate-and-reflect loop.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "core/geometry/spatial_sort.hpp"

namespace tinsmith::geometry {
namespace {

std::uint32_t referenceHilbert13(std::uint32_t x, std::uint32_t y) {
  constexpr std::uint32_t n = 1u << 13;
  std::uint32_t d = 0;
  for (std::uint32_t s = n / 2; s > 0; s /= 2) {
    const std::uint32_t rx = (x & s) ? 1 : 0;
    const std::uint32_t ry = (y & s) ? 1 : 0;
    d += s * s * ((3 * rx) ^ ry);
    if (ry == 0) {
      if (rx == 1) {
        x = n - 1 - x;
        y = n - 1 - y;
      }
      std::swap(x, y);
    }
  }
  return d;
}

TEST(Hilbert, AgreesWithTheReferenceLoop) {
  // Every cell of a coarse sub-grid, the grid's edges, and random cells.
  for (std::uint32_t x = 0; x < 8192; x += 37) {
    for (std::uint32_t y = 0; y < 8192; y += 41) {
      ASSERT_EQ(hilbertIndex13(x, y), referenceHilbert13(x, y)) << x << ", " << y;
    }
  }
  for (std::uint32_t i = 0; i < 8192; ++i) {
    for (const auto& [x, y] : {std::pair{i, 0u}, {i, 8191u}, {0u, i}, {8191u, i}}) {
      ASSERT_EQ(hilbertIndex13(x, y), referenceHilbert13(x, y)) << x << ", " << y;
    }
  }
  std::mt19937 rng(5);
  for (int i = 0; i < 200000; ++i) {
    const std::uint32_t x = rng() & 8191, y = rng() & 8191;
    ASSERT_EQ(hilbertIndex13(x, y), referenceHilbert13(x, y)) << x << ", " << y;
  }
}

TEST(Hilbert, IsABijectionOnASmallCorner) {
  // Consecutive indices are grid neighbours: walk the curve's first 4^6 cells.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> at(4096);
  std::vector<bool> seen(4096, false);
  for (std::uint32_t x = 0; x < 64; ++x) {
    for (std::uint32_t y = 0; y < 64; ++y) {
      const std::uint32_t d = hilbertIndex13(x, y);
      if (d < 4096) {
        ASSERT_FALSE(seen[d]);
        seen[d] = true;
        at[d] = {x, y};
      }
    }
  }
  for (std::uint32_t d = 0; d < 4096; ++d) ASSERT_TRUE(seen[d]) << d;
  for (std::uint32_t d = 1; d < 4096; ++d) {
    const auto [x0, y0] = at[d - 1];
    const auto [x1, y1] = at[d];
    EXPECT_EQ((x0 > x1 ? x0 - x1 : x1 - x0) + (y0 > y1 ? y0 - y1 : y1 - y0), 1u) << d;
  }
}

}  // namespace
}  // namespace tinsmith::geometry
