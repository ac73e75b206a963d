// SplitMix64 (Steele, Lea & Flood 2014): a tiny seeded generator whose
// numbers are the same on every platform and standard library (the std::
// distributions are not), for generated data that must be reproducible bit
// for bit — readers.synthetic, the fitter's test points, benchmarks.
#pragma once

#include <cstdint>

namespace tinsmith {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1): the top 53 bits of next().
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

}  // namespace tinsmith
