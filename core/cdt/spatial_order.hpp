// The CDT's spatial orders and bulk helpers: a growing bounding box, the
// Hilbert index of points over a box, a deterministic chunked parallel-for and
// a stable radix sort on 32-bit keys. Internal to core/cdt.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

#include "core/base/point.hpp"
#include "core/geometry/hilbert.hpp"

namespace tinsmith::cdt {

/// A bounding box that grows by points and boxes.
struct Box {
  double minX = INFINITY, minY = INFINITY, maxX = -INFINITY, maxY = -INFINITY;
  void add(const Point2& p) {
    minX = std::min(minX, p.x);
    maxX = std::max(maxX, p.x);
    minY = std::min(minY, p.y);
    maxY = std::max(maxY, p.y);
  }
  void add(const Box& b) {
    minX = std::min(minX, b.minX);
    maxX = std::max(maxX, b.maxX);
    minY = std::min(minY, b.minY);
    maxY = std::max(maxY, b.maxY);
  }
};

/// Hilbert index (hilbertIndex13) of points on a 2^13 grid over a box.
class HilbertGrid {
 public:
  explicit HilbertGrid(const Box& box)
      : box_(box),
        sx_(box.maxX > box.minX ? kGrid / (box.maxX - box.minX) : 0.0),
        sy_(box.maxY > box.minY ? kGrid / (box.maxY - box.minY) : 0.0) {}
  [[nodiscard]] std::uint32_t operator()(const Point2& p) const {
    const auto gx = static_cast<std::uint32_t>(std::min(kGrid, (p.x - box_.minX) * sx_));
    const auto gy = static_cast<std::uint32_t>(std::min(kGrid, (p.y - box_.minY) * sy_));
    return geometry::hilbertIndex13(gx, gy);
  }

 private:
  static constexpr double kGrid = 8191.0;
  Box box_;
  double sx_, sy_;
};

/// Runs f(chunk, begin, end) over [0, n) split into `threads` contiguous
/// chunks (chunk k on its own thread; chunk 0 on the caller's). Chunk bounds
/// depend only on n and threads.
template <class F>
void parallelChunks(unsigned threads, std::size_t n, const F& f) {
  if (threads <= 1 || n < 4096) {
    f(0u, std::size_t{0}, n);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);
  for (unsigned k = 1; k < threads; ++k) {
    pool.emplace_back([&f, k, n, threads] { f(k, n * k / threads, n * (k + 1) / threads); });
  }
  f(0u, std::size_t{0}, n / threads);
  for (auto& t : pool) t.join();
}

// LSD radix sort of 64-bit values on their upper 32 bits (stable). With
// several threads each sorts its chunk's share into place through per-chunk
// bucket offsets, so the result is the same for any thread count.
inline void radixSortHigh32(std::vector<std::uint64_t>& v, unsigned threads) {
  std::vector<std::uint64_t> tmp(v.size());
  if (v.size() < 4096) threads = 1;
  std::vector<std::array<std::size_t, 256>> count(threads);
  for (int shift = 32; shift < 64; shift += 8) {
    parallelChunks(threads, v.size(), [&](unsigned k, std::size_t b, std::size_t e) {
      count[k].fill(0);
      for (std::size_t i = b; i < e; ++i) ++count[k][(v[i] >> shift) & 0xff];
    });
    std::size_t sum = 0;
    for (int d = 0; d < 256; ++d) {
      for (unsigned k = 0; k < threads; ++k) {
        const std::size_t c = count[k][d];
        count[k][d] = sum;
        sum += c;
      }
    }
    parallelChunks(threads, v.size(), [&](unsigned k, std::size_t b, std::size_t e) {
      auto& off = count[k];
      for (std::size_t i = b; i < e; ++i) tmp[off[(v[i] >> shift) & 0xff]++] = v[i];
    });
    v.swap(tmp);
  }
}


}  // namespace tinsmith::cdt
