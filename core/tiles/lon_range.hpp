// Longitude ranges as 3D Tiles regions have them: west and east in radians in
// [−π, π], the range running eastward from west to east, so east < west is a
// range across the antimeridian; [−π, π] is every longitude. What a tile's
// region needs: the range of a set of longitudes (vertices of a tile, which
// may straddle ±180°), and the smallest range holding two ranges (a parent's
// region grown by its children's).
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

namespace tinsmith::tiles {

struct LonRange {
  double west = -std::numbers::pi, east = std::numbers::pi;
};

inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// `a` in [−π, π].
inline double wrapLongitude(double a) {
  const double w = std::remainder(a, kTwoPi);
  return w == -std::numbers::pi ? std::numbers::pi : w;
}

/// How far east the range reaches from its west end (radians, 0..2π).
inline double lonSpan(const LonRange& r) {
  if (r.west == -std::numbers::pi && r.east == std::numbers::pi) return kTwoPi;
  const double d = r.east - r.west;
  return d >= 0 ? d : d + kTwoPi;
}

inline bool isEveryLongitude(const LonRange& r) {
  return lonSpan(r) >= kTwoPi;
}

/// The range from `west` eastward over `span`; every longitude when the
/// span reaches around.
inline LonRange lonRangeFrom(double west, double span) {
  if (span >= kTwoPi) return {};
  return {wrapLongitude(west), wrapLongitude(west + span)};
}

/// The range of `lons` (radians), unwrapped around `centre`: right for any
/// set that spans less than π on each side of it (a tile, seen from its
/// centre), whatever side of ±180° its points are on.
inline LonRange lonRangeAround(double centre, std::span<const double> lons) {
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const double lon : lons) {
    const double d = wrapLongitude(lon - centre);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  if (lo > hi) return {};
  return lonRangeFrom(centre + lo, hi - lo);
}

/// The smallest range holding both: it starts at the west end of one of them.
inline LonRange lonUnion(const LonRange& a, const LonRange& b) {
  if (isEveryLongitude(a) || isEveryLongitude(b)) return {};
  const double spanA = lonSpan(a), spanB = lonSpan(b);
  // From a's west end: b starts `offset` east of it.
  const auto reach = [](double fromWest, double fromSpan, double otherWest, double otherSpan) {
    double offset = otherWest - fromWest;
    if (offset < 0) offset += kTwoPi;
    return std::max(fromSpan, offset + otherSpan);
  };
  const double fromA = reach(a.west, spanA, b.west, spanB);
  const double fromB = reach(b.west, spanB, a.west, spanA);
  return fromA <= fromB ? lonRangeFrom(a.west, fromA) : lonRangeFrom(b.west, fromB);
}

}  // namespace tinsmith::tiles
