// Plain coordinate types. x, y are in the project CRS (projected, metres,
// UTM-sized values ~7e6 must keep millimetre detail: always double); z is the
// elevation in metres, carried as payload — predicates look at x, y only.
#pragma once

namespace tinsmith {

struct Point2 {
  double x = 0.0;
  double y = 0.0;
  friend bool operator==(const Point2&, const Point2&) = default;
};

struct Point3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
  [[nodiscard]] Point2 xy() const { return {x, y}; }
  friend bool operator==(const Point3&, const Point3&) = default;
};

}  // namespace tinsmith
