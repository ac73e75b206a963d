// Exact fallbacks of the predicates (see predicates.hpp): expansion arithmetic
// after Shewchuk (1997). An expansion is a sum of non-overlapping doubles in
// increasing magnitude; its sign is the sign of its last (largest) component.
// Every operation here is exact (Dekker splitting, Knuth two-sum) as long as
// nothing overflows. Buffers are fixed-size arrays on the stack: the largest
// expansion (incircle with inexact coordinate differences) has at most 1536
// components.
#include "core/geometry/predicates.hpp"

#include <algorithm>
#include <cmath>

namespace tinsmith::geometry {
namespace {

constexpr double kSplitter = 134217729.0;  // 2^27 + 1

inline void twoSum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bVirtual = x - a;
  const double aVirtual = x - bVirtual;
  y = (a - aVirtual) + (b - bVirtual);
}

inline void twoDiff(double a, double b, double& x, double& y) {
  x = a - b;
  const double bVirtual = a - x;
  const double aVirtual = x + bVirtual;
  y = (a - aVirtual) + (bVirtual - b);
}

inline void split(double a, double& hi, double& lo) {
  const double c = kSplitter * a;
  const double big = c - a;
  hi = c - big;
  lo = a - hi;
}

inline void twoProduct(double a, double b, double& x, double& y) {
  x = a * b;
  double ahi, alo, bhi, blo;
  split(a, ahi, alo);
  split(b, bhi, blo);
  const double err1 = x - ahi * bhi;
  const double err2 = err1 - alo * bhi;
  const double err3 = err2 - ahi * blo;
  y = alo * blo - err3;
}

/// An expansion with at most N components; n ≥ 1 always (a lone 0 is zero).
template <int N>
struct Expansion {
  double v[N];
  int n = 0;
  [[nodiscard]] int sign() const {
    const double top = v[n - 1];
    return top > 0 ? 1 : (top < 0 ? -1 : 0);
  }
};

/// h = e + f (exact). Merges by magnitude, then accumulates with two-sum
/// (Shewchuk's fast expansion sum with zero elimination). Returns length ≥ 1.
int sumInto(const double* e, int elen, const double* f, int flen, double* h, double* scratch) {
  // Merge by increasing magnitude.
  int i = 0, j = 0, k = 0;
  while (i < elen && j < flen) {
    if (std::fabs(e[i]) <= std::fabs(f[j])) {
      scratch[k++] = e[i++];
    } else {
      scratch[k++] = f[j++];
    }
  }
  while (i < elen) scratch[k++] = e[i++];
  while (j < flen) scratch[k++] = f[j++];
  int hn = 0;
  double q = scratch[0];
  for (int m = 1; m < k; ++m) {
    double qNew, hh;
    twoSum(q, scratch[m], qNew, hh);
    q = qNew;
    if (hh != 0.0) h[hn++] = hh;
  }
  if (q != 0.0 || hn == 0) h[hn++] = q;
  return hn;
}

/// h = e · b (exact), zero-eliminated. Returns length ≥ 1.
int scaleInto(const double* e, int elen, double b, double* h) {
  double bhi, blo;
  split(b, bhi, blo);
  int hn = 0;
  double q, hh;
  twoProduct(e[0], b, q, hh);
  if (hh != 0.0) h[hn++] = hh;
  for (int i = 1; i < elen; ++i) {
    double p1, p0, sum;
    twoProduct(e[i], b, p1, p0);
    twoSum(q, p0, sum, hh);
    if (hh != 0.0) h[hn++] = hh;
    // Fast two-sum: |p1| ≥ |sum| holds here (Shewchuk, Thm. 19).
    q = p1 + sum;
    hh = sum - (q - p1);
    if (hh != 0.0) h[hn++] = hh;
  }
  if (q != 0.0 || hn == 0) h[hn++] = q;
  return hn;
}

template <int NE, int NF, int NH>
void add(const Expansion<NE>& e, const Expansion<NF>& f, Expansion<NH>& h) {
  static_assert(NH >= NE + NF);
  double scratch[NE + NF];
  h.n = sumInto(e.v, e.n, f.v, f.n, h.v, scratch);
}

template <int NE, int NF, int NH>
void subtract(const Expansion<NE>& e, const Expansion<NF>& f, Expansion<NH>& h) {
  Expansion<NF> neg;
  neg.n = f.n;
  for (int i = 0; i < f.n; ++i) neg.v[i] = -f.v[i];
  add(e, neg, h);
}

/// h = e · f (exact): the sum over f's components of e scaled by each.
template <int NE, int NF, int NH>
void multiply(const Expansion<NE>& e, const Expansion<NF>& f, Expansion<NH>& h) {
  static_assert(NH >= 2 * NE * NF);
  double acc[2][NH];
  double scaled[2 * NE];
  double scratch[NH + 2 * NE];
  int accN = 0;
  int cur = 0;
  acc[0][0] = 0.0;
  accN = 1;
  for (int i = 0; i < f.n; ++i) {
    const int sn = scaleInto(e.v, e.n, f.v[i], scaled);
    accN = sumInto(acc[cur], accN, scaled, sn, acc[1 - cur], scratch);
    cur = 1 - cur;
  }
  std::copy(acc[cur], acc[cur] + accN, h.v);
  h.n = accN;
}

Expansion<2> difference(double a, double b) {
  Expansion<2> r;
  double x, y;
  twoDiff(a, b, x, y);
  r.n = 0;
  if (y != 0.0) r.v[r.n++] = y;
  r.v[r.n++] = x;
  return r;
}

}  // namespace

namespace detail {

int orient2dExact(double ax, double ay, double bx, double by, double cx, double cy) {
  const Expansion<2> acx = difference(ax, cx), acy = difference(ay, cy);
  const Expansion<2> bcx = difference(bx, cx), bcy = difference(by, cy);
  Expansion<8> left, right;
  multiply(acx, bcy, left);
  multiply(acy, bcx, right);
  Expansion<16> det;
  subtract(left, right, det);
  return det.sign();
}

int incircleExact(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                  double dy) {
  const Expansion<2> adx = difference(ax, dx), ady = difference(ay, dy);
  const Expansion<2> bdx = difference(bx, dx), bdy = difference(by, dy);
  const Expansion<2> cdx = difference(cx, dx), cdy = difference(cy, dy);

  auto cross = [](const Expansion<2>& px, const Expansion<2>& py, const Expansion<2>& qx,
                  const Expansion<2>& qy, Expansion<16>& out) {
    Expansion<8> l, r;
    multiply(px, qy, l);
    multiply(qx, py, r);
    subtract(l, r, out);
  };
  auto lift = [](const Expansion<2>& px, const Expansion<2>& py, Expansion<16>& out) {
    Expansion<8> xx, yy;
    multiply(px, px, xx);
    multiply(py, py, yy);
    add(xx, yy, out);
  };

  Expansion<16> bc, ca, ab, alift, blift, clift;
  cross(bdx, bdy, cdx, cdy, bc);  // bdx*cdy - cdx*bdy
  cross(cdx, cdy, adx, ady, ca);  // cdx*ady - adx*cdy
  cross(adx, ady, bdx, bdy, ab);  // adx*bdy - bdx*ady
  lift(adx, ady, alift);
  lift(bdx, bdy, blift);
  lift(cdx, cdy, clift);

  Expansion<512> ta, tb, tc;
  multiply(alift, bc, ta);
  multiply(blift, ca, tb);
  multiply(clift, ab, tc);
  Expansion<1024> tab;
  add(ta, tb, tab);
  Expansion<1536> det;
  add(tab, tc, det);
  return det.sign();
}

}  // namespace detail

bool onSegment(const Point2& a, const Point2& b, const Point2& c) {
  if (orient2d(a, b, c) != 0) return false;
  return std::min(a.x, b.x) <= c.x && c.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= c.y &&
         c.y <= std::max(a.y, b.y);
}

SegmentIntersection segmentIntersection(const Point2& p0, const Point2& p1, const Point2& q0,
                                        const Point2& q1) {
  const int o1 = orient2d(p0, p1, q0);
  const int o2 = orient2d(p0, p1, q1);
  const int o3 = orient2d(q0, q1, p0);
  const int o4 = orient2d(q0, q1, p1);
  if (o1 * o2 < 0 && o3 * o4 < 0) return SegmentIntersection::Proper;
  if (o1 == 0 && o2 == 0 && o3 == 0 && o4 == 0) {
    // Collinear (or degenerate): compare projections on the dominant axis.
    const bool useX = std::max(std::fabs(p1.x - p0.x), std::fabs(q1.x - q0.x)) >=
                      std::max(std::fabs(p1.y - p0.y), std::fabs(q1.y - q0.y));
    auto key = [useX](const Point2& p) { return useX ? p.x : p.y; };
    const double pLo = std::min(key(p0), key(p1)), pHi = std::max(key(p0), key(p1));
    const double qLo = std::min(key(q0), key(q1)), qHi = std::max(key(q0), key(q1));
    const double lo = std::max(pLo, qLo), hi = std::min(pHi, qHi);
    if (lo > hi) return SegmentIntersection::None;
    if (lo == hi) {
      // Share one point — unless both are the same single point.
      return SegmentIntersection::Touching;
    }
    return SegmentIntersection::Overlap;
  }
  if ((o1 == 0 && onSegment(p0, p1, q0)) || (o2 == 0 && onSegment(p0, p1, q1)) ||
      (o3 == 0 && onSegment(q0, q1, p0)) || (o4 == 0 && onSegment(q0, q1, p1))) {
    return SegmentIntersection::Touching;
  }
  return SegmentIntersection::None;
}

Point2 intersectionPoint(const Point2& p0, const Point2& p1, const Point2& q0, const Point2& q1) {
  // Signed areas of p0 and p1 against the line q0q1, computed in doubles.
  const double ex = q1.x - q0.x, ey = q1.y - q0.y;
  const double d0 = ex * (p0.y - q0.y) - ey * (p0.x - q0.x);
  const double d1 = ex * (p1.y - q0.y) - ey * (p1.x - q0.x);
  const double denom = d0 - d1;
  double t = denom != 0.0 ? d0 / denom : 0.5;
  t = std::clamp(t, 0.0, 1.0);
  Point2 r;
  // Interpolate from the nearer end for accuracy.
  if (t <= 0.5) {
    r = {p0.x + t * (p1.x - p0.x), p0.y + t * (p1.y - p0.y)};
  } else {
    const double s = 1.0 - t;
    r = {p1.x + s * (p0.x - p1.x), p1.y + s * (p0.y - p1.y)};
  }
  const double loX = std::max(std::min(p0.x, p1.x), std::min(q0.x, q1.x));
  const double hiX = std::min(std::max(p0.x, p1.x), std::max(q0.x, q1.x));
  const double loY = std::max(std::min(p0.y, p1.y), std::min(q0.y, q1.y));
  const double hiY = std::min(std::max(p0.y, p1.y), std::max(q0.y, q1.y));
  if (loX <= hiX) r.x = std::clamp(r.x, loX, hiX);
  if (loY <= hiY) r.y = std::clamp(r.y, loY, hiY);
  return r;
}

}  // namespace tinsmith::geometry
