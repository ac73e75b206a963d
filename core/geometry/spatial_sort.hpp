// Spatial sorting: the space-filling curves tinsmith orders points by and
// the radix sorts that order them in linear time. The CDT inserts along the
// Hilbert curve (locality for the walk); the fitter sorts along the Morton
// (Z-order) curve, whose cells of every level are contiguous runs.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace tinsmith::geometry {

// Hilbert index of (x, y) on a 2^13 grid (26 bits), two levels a step: a
// state (the curve's orientation in the current square, 0..3) and two bits of
// x and of y give four bits of the index and the next state. The tables were
// derived from the textbook rotate-and-reflect loop and agree with it on the
// whole grid (tests/core/hilbert_test.cpp).
inline std::uint32_t hilbertIndex13(std::uint32_t x, std::uint32_t y) {
  // One level: state*4 + (x bit << 1 | y bit) -> digit << 2 | next state.
  static constexpr std::uint8_t kOne[16] = {1, 4, 14, 8, 0, 15, 5, 9, 10, 6, 12, 3, 11, 13, 7, 2};
  // Two levels: state*16 + (2 bits of x) * 4 + (2 bits of y) -> 4 index bits
  // << 2 | next state.
  static constexpr std::uint8_t kTwo[64] = {
      0,  15, 17, 20, 5,  9,  30, 24, 58, 54, 33, 36, 60, 51, 46, 40, 1,  4,  59, 61, 14, 8,
      55, 50, 16, 31, 32, 47, 21, 25, 37, 41, 42, 38, 26, 22, 44, 35, 28, 19, 49, 52, 11, 13,
      62, 56, 7,  2,  43, 45, 48, 63, 39, 34, 53, 57, 27, 29, 10, 6,  23, 18, 12, 3};
  std::uint32_t e = kOne[((x >> 12) & 1) << 1 | ((y >> 12) & 1)];
  std::uint32_t d = e >> 2, state = e & 3;
  for (int b = 10; b >= 0; b -= 2) {
    e = kTwo[state * 16 + ((x >> b) & 3) * 4 + ((y >> b) & 3)];
    d = (d << 4) | (e >> 2);
    state = e & 3;
  }
  return d;
}

/// Morton code interleaving: the low 32 bits of v spread to the even bits.
inline std::uint64_t spreadBits(std::uint64_t v) {
  v &= 0xffffffffULL;
  v = (v | (v << 16)) & 0x0000ffff0000ffffULL;
  v = (v | (v << 8)) & 0x00ff00ff00ff00ffULL;
  v = (v | (v << 4)) & 0x0f0f0f0f0f0f0f0fULL;
  v = (v | (v << 2)) & 0x3333333333333333ULL;
  v = (v | (v << 1)) & 0x5555555555555555ULL;
  return v;
}

/// The inverse of spreadBits: the even bits of v packed into the low 32.
inline std::uint64_t compactBits(std::uint64_t v) {
  v &= 0x5555555555555555ULL;
  v = (v | (v >> 1)) & 0x3333333333333333ULL;
  v = (v | (v >> 2)) & 0x0f0f0f0f0f0f0f0fULL;
  v = (v | (v >> 4)) & 0x00ff00ff00ff00ffULL;
  v = (v | (v >> 8)) & 0x0000ffff0000ffffULL;
  v = (v | (v >> 16)) & 0x00000000ffffffffULL;
  return v;
}

/// Sorts (code, index) pairs by code with a stable LSD radix sort over the
/// low `bits` bits of the codes (11 bits a pass): linear in the points.
inline void radixSortByCode(std::vector<std::pair<std::uint64_t, std::uint32_t>>& v, int bits) {
  constexpr int kDigit = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigit;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> tmp(v.size());
  std::vector<std::size_t> offset(kBuckets);
  for (int sh = 0; sh < bits; sh += kDigit) {
    std::fill(offset.begin(), offset.end(), 0);
    for (const auto& e : v) ++offset[(e.first >> sh) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (auto& o : offset) {
      const std::size_t c = o;
      o = sum;
      sum += c;
    }
    for (const auto& e : v) tmp[offset[(e.first >> sh) & (kBuckets - 1)]++] = e;
    v.swap(tmp);
  }
}

}  // namespace tinsmith::geometry
