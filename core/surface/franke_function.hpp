// Franke's function on [0, 1]² (the book's (8.14)): the classic test surface
// of scattered-data fitting. The fitter's tests and benchmarks compare against
// it, and readers.synthetic samples it (surface=franke). Values lie in about
// [0, 1.22]; smooth, with two peaks and a dip.
#pragma once

#include <cmath>

namespace tinsmith {

inline double frankeFunction(double x, double y) {
  return 0.75 * std::exp(-((9 * x - 2) * (9 * x - 2) + (9 * y - 2) * (9 * y - 2)) / 4) +
         0.75 * std::exp(-((9 * x + 1) * (9 * x + 1)) / 49 - (9 * y + 1) / 10) +
         0.5 * std::exp(-((9 * x - 7) * (9 * x - 7) + (9 * y - 3) * (9 * y - 3)) / 4) -
         0.2 * std::exp(-(9 * x - 4) * (9 * x - 4) - (9 * y - 7) * (9 * y - 7));
}

}  // namespace tinsmith
