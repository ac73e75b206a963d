// The exact predicates against an independent exact evaluation: every double is
// an integer times a power of two, so scaling all inputs to their smallest
// exponent turns the determinants into big-integer arithmetic.
#include "core/geometry/predicates.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace tinsmith::geometry {
namespace {

/// Minimal signed big integer (base 2^32 magnitude) with +, −, ×.
struct BigInt {
  bool negative = false;
  std::vector<std::uint32_t> mag;  // little-endian, no leading zeros

  void trim() {
    while (!mag.empty() && mag.back() == 0) mag.pop_back();
    if (mag.empty()) negative = false;
  }
  [[nodiscard]] int sign() const { return mag.empty() ? 0 : (negative ? -1 : 1); }

  static int cmpMag(const std::vector<std::uint32_t>& a, const std::vector<std::uint32_t>& b) {
    if (a.size() != b.size()) return a.size() < b.size() ? -1 : 1;
    for (std::size_t i = a.size(); i-- > 0;) {
      if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
    }
    return 0;
  }
  static std::vector<std::uint32_t> addMag(const std::vector<std::uint32_t>& a,
                                           const std::vector<std::uint32_t>& b) {
    std::vector<std::uint32_t> r(std::max(a.size(), b.size()) + 1, 0);
    std::uint64_t carry = 0;
    for (std::size_t i = 0; i < r.size(); ++i) {
      std::uint64_t s = carry;
      if (i < a.size()) s += a[i];
      if (i < b.size()) s += b[i];
      r[i] = static_cast<std::uint32_t>(s);
      carry = s >> 32;
    }
    return r;
  }
  static std::vector<std::uint32_t> subMag(const std::vector<std::uint32_t>& a,
                                           const std::vector<std::uint32_t>& b) {  // a ≥ b
    std::vector<std::uint32_t> r(a.size(), 0);
    std::int64_t borrow = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      std::int64_t d = static_cast<std::int64_t>(a[i]) - borrow - (i < b.size() ? b[i] : 0);
      borrow = d < 0;
      if (d < 0) d += (std::int64_t{1} << 32);
      r[i] = static_cast<std::uint32_t>(d);
    }
    return r;
  }
  friend BigInt operator+(const BigInt& a, const BigInt& b) {
    BigInt r;
    if (a.negative == b.negative) {
      r.mag = addMag(a.mag, b.mag);
      r.negative = a.negative;
    } else if (cmpMag(a.mag, b.mag) >= 0) {
      r.mag = subMag(a.mag, b.mag);
      r.negative = a.negative;
    } else {
      r.mag = subMag(b.mag, a.mag);
      r.negative = b.negative;
    }
    r.trim();
    return r;
  }
  friend BigInt operator-(const BigInt& a, const BigInt& b) {
    BigInt nb = b;
    nb.negative = !nb.negative;
    nb.trim();
    return a + nb;
  }
  friend BigInt operator*(const BigInt& a, const BigInt& b) {
    BigInt r;
    r.mag.assign(a.mag.size() + b.mag.size() + 1, 0);
    for (std::size_t i = 0; i < a.mag.size(); ++i) {
      std::uint64_t carry = 0;
      for (std::size_t j = 0; j < b.mag.size(); ++j) {
        const std::uint64_t cur =
            static_cast<std::uint64_t>(a.mag[i]) * b.mag[j] + r.mag[i + j] + carry;
        r.mag[i + j] = static_cast<std::uint32_t>(cur);
        carry = cur >> 32;
      }
      std::size_t k = i + b.mag.size();
      while (carry) {
        const std::uint64_t cur = static_cast<std::uint64_t>(r.mag[k]) + carry;
        r.mag[k++] = static_cast<std::uint32_t>(cur);
        carry = cur >> 32;
      }
    }
    r.negative = a.negative != b.negative;
    r.trim();
    return r;
  }
};

/// Exponent e with x = m·2^e, m a 53-bit integer.
int exponentOf(double x) {
  int k;
  std::frexp(x, &k);
  return k - 53;
}

/// x / 2^base as a big integer (exact: base ≤ exponentOf(x)).
BigInt scaled(double x, int base) {
  BigInt r;
  if (x == 0) return r;
  int k;
  const double f = std::frexp(std::fabs(x), &k);
  auto m = static_cast<std::uint64_t>(std::ldexp(f, 53));
  const int shift = k - 53 - base;
  r.mag = {static_cast<std::uint32_t>(m), static_cast<std::uint32_t>(m >> 32)};
  // Shift left by `shift` bits.
  const int words = shift / 32, bits = shift % 32;
  std::vector<std::uint32_t> out(r.mag.size() + words + 1, 0);
  for (std::size_t i = 0; i < r.mag.size(); ++i) {
    const std::uint64_t v = static_cast<std::uint64_t>(r.mag[i]) << bits;
    out[i + words] |= static_cast<std::uint32_t>(v);
    out[i + words + 1] |= static_cast<std::uint32_t>(v >> 32);
  }
  r.mag = out;
  r.negative = x < 0;
  r.trim();
  return r;
}

int baseOf(std::initializer_list<double> xs) {
  int base = 100000;
  for (double x : xs) {
    if (x != 0) base = std::min(base, exponentOf(x));
  }
  return base == 100000 ? 0 : base;
}

int orientExact(Point2 a, Point2 b, Point2 c) {
  const int e = baseOf({a.x, a.y, b.x, b.y, c.x, c.y});
  const BigInt ax = scaled(a.x, e), ay = scaled(a.y, e), bx = scaled(b.x, e),
               by = scaled(b.y, e), cx = scaled(c.x, e), cy = scaled(c.y, e);
  return ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)).sign();
}

int incircleExact(Point2 a, Point2 b, Point2 c, Point2 d) {
  const int e = baseOf({a.x, a.y, b.x, b.y, c.x, c.y, d.x, d.y});
  const BigInt dx = scaled(d.x, e), dy = scaled(d.y, e);
  const BigInt ax = scaled(a.x, e) - dx, ay = scaled(a.y, e) - dy;
  const BigInt bx = scaled(b.x, e) - dx, by = scaled(b.y, e) - dy;
  const BigInt cx = scaled(c.x, e) - dx, cy = scaled(c.y, e) - dy;
  const BigInt al = ax * ax + ay * ay, bl = bx * bx + by * by, cl = cx * cx + cy * cy;
  return (al * (bx * cy - cx * by) - bl * (ax * cy - cx * ay) + cl * (ax * by - bx * ay)).sign();
}

#if defined(__SANITIZE_ADDRESS__)
constexpr int kCases = 3000;  // the big-integer reference is slow unoptimised
#else
constexpr int kCases = 20000;
#endif

double ulps(double x, int k) {
  for (; k > 0; --k) x = std::nextafter(x, INFINITY);
  for (; k < 0; ++k) x = std::nextafter(x, -INFINITY);
  return x;
}

TEST(Predicates, BigIntReferenceSanity) {
  EXPECT_EQ(orientExact({0, 0}, {1, 0}, {0, 1}), 1);
  EXPECT_EQ(orientExact({0, 0}, {1, 0}, {2, 0}), 0);
  EXPECT_EQ(orientExact({0, 0}, {0, 1}, {1, 0}), -1);
  EXPECT_EQ(incircleExact({1, 0}, {0, 1}, {-1, 0}, {0, 0}), 1);
  EXPECT_EQ(incircleExact({1, 0}, {0, 1}, {-1, 0}, {0, -1}), 0);
  EXPECT_EQ(incircleExact({1, 0}, {0, 1}, {-1, 0}, {0, -2}), -1);
}

TEST(Predicates, OrientOnLineOffsetByUlps) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> d(-1000, 1000);
  std::uniform_int_distribution<int> k(-3, 3);
  std::uniform_real_distribution<double> t(-0.5, 1.5);
  int disagreements = 0, zeros = 0, n = 0;
  for (int i = 0; i < kCases; ++i) {
    const Point2 a{d(rng), d(rng)}, b{d(rng), d(rng)};
    const double s = t(rng);
    Point2 c{a.x + s * (b.x - a.x), a.y + s * (b.y - a.y)};
    c.x = ulps(c.x, k(rng));
    c.y = ulps(c.y, k(rng));
    const int expect = orientExact(a, b, c);
    zeros += expect == 0;
    ++n;
    disagreements += orient2d(a, b, c) != expect;
    disagreements += orient2d(b, c, a) != expect;
    disagreements += orient2d(b, a, c) != -expect;
  }
  // Exactly collinear integer triples, then one ulp off.
  std::uniform_int_distribution<int> ii(-1000000, 1000000);
  for (int i = 0; i < kCases; ++i) {
    const Point2 a{double(ii(rng)), double(ii(rng))};
    const int dx = ii(rng) % 1000, dy = ii(rng) % 1000, s = ii(rng) % 300;
    const Point2 b{a.x + dx, a.y + dy};
    Point2 c{a.x + s * dx, a.y + s * dy};
    if (i % 2) c.x = ulps(c.x, i % 4 == 1 ? 1 : -1);
    const int expect = orientExact(a, b, c);
    zeros += expect == 0;
    ++n;
    disagreements += orient2d(a, b, c) != expect;
    disagreements += orient2d(c, a, b) != expect;
  }
  EXPECT_EQ(disagreements, 0) << "of " << n;
  EXPECT_GT(zeros, kCases / 4);
}

TEST(Predicates, OrientUtmCoordinatesWithMillimetreOffsets) {
  std::mt19937_64 rng(2);
  std::uniform_int_distribution<int> mm(-5000, 5000);
  int disagreements = 0, zeros = 0;
  for (int i = 0; i < kCases; ++i) {
    const double x0 = 500000.0, y0 = 7000000.0;
    const Point2 a{x0 + mm(rng) * 0.001, y0 + mm(rng) * 0.001};
    const Point2 b{a.x + 0.001 * (i % 7 + 1), a.y + 0.002 * (i % 5 + 1)};
    // On the line through a, b in decimal terms; rounding makes it near-degenerate.
    const int s = mm(rng) % 50;
    const Point2 c{a.x + (b.x - a.x) * s, a.y + (b.y - a.y) * s + 0.001 * (i % 3 - 1)};
    const int expect = orientExact(a, b, c);
    zeros += expect == 0;
    disagreements += orient2d(a, b, c) != expect;
  }
  EXPECT_EQ(disagreements, 0);
  EXPECT_GT(zeros, 0);
}

TEST(Predicates, IncircleNearlyCocircular) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ang(0, 2 * std::numbers::pi);
  std::uniform_int_distribution<int> k(-2, 2);
  int disagreements = 0, nonPositive = 0, nonNegative = 0;
  for (int i = 0; i < kCases; ++i) {
    const double cx = i % 2 ? 7000000.0 : 0.0, cy = i % 2 ? 500000.0 : 0.0;
    const double r = i % 3 == 0 ? 1.0 : (i % 3 == 1 ? 0.01 : 1000.0);
    Point2 p[4];
    for (auto& q : p) {
      const double a = ang(rng);
      q = {cx + r * std::cos(a), cy + r * std::sin(a)};
    }
    p[3].x = ulps(p[3].x, k(rng));
    p[3].y = ulps(p[3].y, k(rng));
    const int expect = incircleExact(p[0], p[1], p[2], p[3]);
    nonPositive += expect <= 0;
    nonNegative += expect >= 0;
    disagreements += incircle(p[0], p[1], p[2], p[3]) != expect;
    disagreements += incircle(p[1], p[0], p[2], p[3]) != -expect;
  }
  EXPECT_EQ(disagreements, 0);
  EXPECT_GT(nonPositive, 0);
  EXPECT_GT(nonNegative, 0);
}

TEST(Predicates, IncircleExactlyCocircularIntegers) {
  // Points of x² + y² = 65² (many integer solutions) at UTM-sized offsets.
  const std::vector<Point2> circle{{65, 0}, {63, 16}, {60, 25}, {56, 33}, {52, 39},
                                   {39, 52}, {33, 56}, {25, 60}, {16, 63}, {0, 65},
                                   {-16, 63}, {-33, -56}, {-60, -25}};
  int disagreements = 0;
  for (double off : {0.0, 7000000.0, 0.5}) {
    for (std::size_t i = 0; i + 3 < circle.size(); ++i) {
      Point2 q[4];
      for (int j = 0; j < 4; ++j) q[j] = {circle[i + j].x + off, circle[i + j].y + off};
      const int expect = incircleExact(q[0], q[1], q[2], q[3]);
      EXPECT_EQ(expect, 0);
      disagreements += incircle(q[0], q[1], q[2], q[3]) != expect;
      Point2 in = q[3];
      in.y = ulps(in.y, in.y > off ? -1 : 1);  // y is never 0 here (no underflow)
      disagreements += incircle(q[0], q[1], q[2], in) != incircleExact(q[0], q[1], q[2], in);
    }
  }
  EXPECT_EQ(disagreements, 0);
}

TEST(Predicates, TinyAndHugeMagnitudes) {
  int disagreements = 0;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> d(-1, 1);
  for (double scale : {1e-30, 1e-5, 1e20, 1e60}) {
    for (int i = 0; i < kCases / 10; ++i) {
      const Point2 a{d(rng) * scale, d(rng) * scale}, b{d(rng) * scale, d(rng) * scale};
      Point2 c{(a.x + b.x) / 2, (a.y + b.y) / 2};
      c.x = ulps(c.x, i % 3 - 1);
      disagreements += orient2d(a, b, c) != orientExact(a, b, c);
      const Point2 e{ulps(-a.x, 1), ulps(-a.y, -1)};
      disagreements += incircle(a, b, c, e) != incircleExact(a, b, c, e);
    }
  }
  EXPECT_EQ(disagreements, 0);
}

TEST(Predicates, SegmentIntersectionKinds) {
  using SI = SegmentIntersection;
  EXPECT_EQ(segmentIntersection({0, 0}, {2, 2}, {0, 2}, {2, 0}), SI::Proper);
  EXPECT_EQ(segmentIntersection({0, 0}, {2, 2}, {1, 1}, {2, 0}), SI::Touching);
  EXPECT_EQ(segmentIntersection({0, 0}, {2, 0}, {1, 0}, {3, 0}), SI::Overlap);
  EXPECT_EQ(segmentIntersection({0, 0}, {1, 0}, {1, 0}, {3, 0}), SI::Touching);
  EXPECT_EQ(segmentIntersection({0, 0}, {1, 0}, {2, 0}, {3, 0}), SI::None);
  EXPECT_EQ(segmentIntersection({0, 0}, {1, 1}, {0, 1}, {0.4, 0.5}), SI::None);
  // One ulp off a line through the other segment's end.
  const double y = std::nextafter(1.0, 2.0);
  EXPECT_EQ(segmentIntersection({0, 0}, {2, 2}, {1, y}, {5, 7}), SI::None);
  EXPECT_TRUE(onSegment({0, 0}, {4, 4}, {3, 3}));
  EXPECT_FALSE(onSegment({0, 0}, {4, 4}, {5, 5}));
  const Point2 x = intersectionPoint({0, 0}, {2, 2}, {0, 2}, {2, 0});
  EXPECT_DOUBLE_EQ(x.x, 1.0);
  EXPECT_DOUBLE_EQ(x.y, 1.0);
}

}  // namespace
}  // namespace tinsmith::geometry
