// Exact geometric predicates on doubles: the only place in tinsmith that takes
// the sign of a determinant. Each predicate first evaluates the determinant in
// floating point and accepts the sign when it exceeds a proven error bound
// (Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates", 1997); otherwise it falls back to exact expansion
// arithmetic (predicates.cpp). The result is the sign of the exact real
// determinant for every finite double input whose intermediate products
// neither overflow nor underflow: coordinate differences (when non-zero)
// between ~1e-70 and ~1e70 in magnitude for incircle (degree 4), ~1e-140 and
// ~1e150 for orient2d — far beyond any terrain. Only x, y are looked at.
#pragma once

#include <cmath>

#include "core/base/point.hpp"

namespace tinsmith::geometry {

namespace detail {
// Error-bound constants from Shewchuk's predicates.c with epsilon = 2^-53.
inline constexpr double kEpsilon = 1.1102230246251565e-16;
inline constexpr double kCcwErrBoundA = (3.0 + 16.0 * kEpsilon) * kEpsilon;
inline constexpr double kIccErrBoundA = (10.0 + 96.0 * kEpsilon) * kEpsilon;

/// Exact sign of orient2d, called when the filter cannot decide.
int orient2dExact(double ax, double ay, double bx, double by, double cx, double cy);
/// Exact sign of incircle, called when the filter cannot decide.
int incircleExact(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                  double dy);
}  // namespace detail

/// Sign of the orientation of (a, b, c): +1 if c lies to the left of the
/// directed line a→b (a, b, c counter-clockwise), −1 to the right, 0 collinear.
inline int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const double detLeft = (ax - cx) * (by - cy);
  const double detRight = (ay - cy) * (bx - cx);
  const double det = detLeft - detRight;
  double detSum;
  if (detLeft > 0.0) {
    if (detRight <= 0.0) return det > 0.0 ? 1 : (det < 0.0 ? -1 : 0);
    detSum = detLeft + detRight;
  } else if (detLeft < 0.0) {
    if (detRight >= 0.0) return det > 0.0 ? 1 : (det < 0.0 ? -1 : 0);
    detSum = -detLeft - detRight;
  } else {
    return det > 0.0 ? 1 : (det < 0.0 ? -1 : 0);
  }
  const double errBound = detail::kCcwErrBoundA * detSum;
  if (det > errBound) return 1;
  if (-det > errBound) return -1;
  return detail::orient2dExact(ax, ay, bx, by, cx, cy);
}

inline int orient2d(const Point2& a, const Point2& b, const Point2& c) {
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

/// Sign of the incircle determinant: +1 if d lies strictly inside the circle
/// through a, b, c when (a, b, c) is counter-clockwise (the sign flips for a
/// clockwise triple), −1 outside, 0 cocircular (or a, b, c collinear and d on
/// their line).
inline int incircle(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                    double dy) {
  const double adx = ax - dx, ady = ay - dy;
  const double bdx = bx - dx, bdy = by - dy;
  const double cdx = cx - dx, cdy = cy - dy;
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double alift = adx * adx + ady * ady;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double blift = bdx * bdx + bdy * bdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double clift = cdx * cdx + cdy * cdy;
  const double det =
      alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * alift +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * blift +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * clift;
  const double errBound = detail::kIccErrBoundA * permanent;
  if (det > errBound) return 1;
  if (-det > errBound) return -1;
  return detail::incircleExact(ax, ay, bx, by, cx, cy, dx, dy);
}

inline int incircle(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  return incircle(a.x, a.y, b.x, b.y, c.x, c.y, d.x, d.y);
}

/// How two closed segments p0p1 and q0q1 meet, decided exactly.
enum class SegmentIntersection {
  None,      ///< disjoint
  Proper,    ///< cross at one point interior to both
  Touching,  ///< meet at one point that is an endpoint of at least one (T-junction, shared end)
  Overlap,   ///< collinear and share more than one point
};

/// Exact classification of how segments p0p1 and q0q1 meet (degenerate
/// zero-length segments are treated as points).
SegmentIntersection segmentIntersection(const Point2& p0, const Point2& p1, const Point2& q0,
                                        const Point2& q1);

/// Twice the signed area of (a, b, c) — positive when counter-clockwise — in
/// plain floating point: an INEXACT orientation, for constructions (areas,
/// gradients, barycentric weights) and for decisions where a wrong sign near
/// zero is harmless. Its sign is not a predicate; orient2d is. Works on any
/// point type with x and y.
template <class P>
[[nodiscard]] inline double orient2dInexact(const P& a, const P& b, const P& c) {
  return (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
}

/// True if c lies on the closed segment ab (exactly: collinear and within the
/// bounding box).
bool onSegment(const Point2& a, const Point2& b, const Point2& c);

/// The intersection point of the lines p0p1 and q0q1, rounded to doubles (an
/// inexact construction; the caller decides with predicates what to do with
/// it). Precondition: the segments cross properly. The result is clamped to
/// the intersection of the two segments' bounding boxes.
Point2 intersectionPoint(const Point2& p0, const Point2& p1, const Point2& q0, const Point2& q1);

}  // namespace tinsmith::geometry
