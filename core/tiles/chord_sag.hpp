// Earth curvature under straight triangles: tile content is drawn as flat
// triangles between points on the (curved) Earth, in ECEF or a local
// east-north-up frame, so a triangle sags below the ground its corners are on
// (to second order, a sphere: L² / 8R at the middle of a chord of length L;
// 8 m for 20 km). The tiler plans with these (a triangle's sag counts in its
// error, a tile side is cut into chords short enough); the declared error and
// bounds measure the sag of every encoded triangle on the ellipsoid itself
// (tile_content.hpp).
#pragma once

#include <algorithm>

#include "core/base/point.hpp"

namespace tinsmith::tiles {

/// The smallest radius of curvature of the WGS84 ellipsoid (the meridian's at
/// the equator, a(1 − e²)), metres: the Earth the tiler plans chords for.
inline constexpr double kEarthRadiusOfCurvature = 6335439.327;

class GeoReference;  // tile_content.hpp
struct Rect;         // pyramid.hpp

/// The radius the tiler plans chord sag with over `square` of a project CRS
/// (a tile's: the bending of a projection varies over a continent):
/// kEarthRadiusOfCurvature, unless the projection bends its straight lines
/// away from the ground so that a segment's chord (between its ends' places
/// on the ellipsoid) lies more than 1 % farther from the ground at its middle
/// than L²/8R says — then that radius shrunk to bound the farthest, with 5 %
/// to spare — or that lies less than half as far at every one (a projection
/// that stretches the ground: Mercator far from the equator) — then that
/// radius grown to bound the farthest, with 25 % to spare. The distance is
/// the whole 3-D gap, as a tile declares it: on a parallel, the chord also
/// leaves the ground sideways (tan φ / R). Measured at the
/// middles of segments in four directions at 25 places over the square (1/8
/// of its width long, from 1 to 20 km); places off the CRS's domain are left
/// out. CONUS Albers across 3 000 km: 0.84 of it; a UTM zone: the sphere's;
/// World Mercator at 75°N: about 3.1 times it (its scale is 3.9 there).
double chordSagRadius(const GeoReference& geo, const Rect& square);

/// Where the plane through a triangle's corners lies deepest below a sphere
/// through them, and how deep: for an acute triangle at its circumcentre,
/// circumradius² / 2R; otherwise at the middle of its longest edge, where
/// the sphere's closest point to the circumcentre is, (longest)² / 8R. x, y
/// in metres (the ground's); to second order in size / R.
struct ChordSag {
  double depth = 0.0;
  Point2 at;
};

inline ChordSag chordSag(Point2 a, Point2 b, Point2 c, double radius) {
  const auto d2 = [](Point2 p, Point2 q) {
    return (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y);
  };
  const double la = d2(b, c), lb = d2(c, a), lc = d2(a, b);  // opposite a, b, c
  const double longest = std::max({la, lb, lc});
  if (2 * longest >= la + lb + lc) {  // right or obtuse (or degenerate)
    const Point2 m = longest == la   ? Point2{0.5 * (b.x + c.x), 0.5 * (b.y + c.y)}
                     : longest == lb ? Point2{0.5 * (c.x + a.x), 0.5 * (c.y + a.y)}
                                     : Point2{0.5 * (a.x + b.x), 0.5 * (a.y + b.y)};
    return {longest / (8 * radius), m};
  }
  // The circumcentre, from a.
  const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  const double d = 2 * (bx * cy - by * cx);
  const double b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
  const double ux = (cy * b2 - by * c2) / d, uy = (bx * c2 - cx * b2) / d;
  return {(ux * ux + uy * uy) / (2 * radius), {a.x + ux, a.y + uy}};
}

/// The largest value over a triangle of a gap that is quadratic over it and
/// zero at its corners (a flat triangle against the curved ground under it,
/// to second order), from the gaps at its edges' middles (≥ 0; the edge
/// from corner 0 to 1, 1 to 2, 2 to 0): with barycentric w, the gap is
/// 4 · Σ mid_ij · w_i · w_j, whose largest value is at an edge's middle or at
/// its one stationary point inside (at most 4/3 of the largest middle, for
/// equal middles). For gaps that are vectors, the lengths give a bound.
inline double quadraticGapMax(double mid01, double mid12, double mid20) {
  double best = std::max({mid01, mid12, mid20});
  const double a = 4 * mid12, b = 4 * mid20, c = 4 * mid01;  // opposite corners 0, 1, 2
  if (a > 0 && b > 0 && c > 0) {
    // The stationary point of the form on w0 + w1 + w2 = 1: H·w ∝ 1.
    const double w0 = (b + c - a) / (2 * b * c), w1 = (a + c - b) / (2 * a * c),
                 w2 = (a + b - c) / (2 * a * b);
    if (w0 > 0 && w1 > 0 && w2 > 0) best = std::max(best, 0.5 / (w0 + w1 + w2));
  }
  return best;
}

}  // namespace tinsmith::tiles
