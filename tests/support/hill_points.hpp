// A small hill of 31 × 31 spot heights at UTM 12N-sized coordinates (25 m
// apart, slightly irregular), for CLI tests that need a quick TIN to tile.
#pragma once

#include <cmath>
#include <ostream>

namespace tinsmith::test {

/// Writes "x<sep>y<sep>z" lines, full precision.
inline void writeHillPoints(std::ostream& out, char sep) {
  out.precision(17);
  for (int j = 0; j <= 30; ++j)
    for (int i = 0; i <= 30; ++i) {
      const double x = 430000 + i * 25.0 + (i % 3) * 1.7, y = 4515000 + j * 25.0 + (j % 4) * 1.3;
      const double z =
          1600 + 80 * std::exp(-(std::pow(i - 12, 2) + std::pow(j - 17, 2)) / 60.0) + 0.3 * i;
      out << x << sep << y << sep << z << "\n";
    }
}

}  // namespace tinsmith::test
