// Deterministic test data for the fitter: a seeded generator (no std::
// distributions, whose output differs between standard libraries), Franke's
// function sampled unevenly, and small triangulations with a brute-force locator.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/base/point.hpp"
#include "core/base/split_mix.hpp"
#include "core/fit/least_squares.hpp"
#include "core/fit/multilevel_fit.hpp"
#include "core/surface/franke_function.hpp"

namespace tinsmith::fit::testing {

/// The portable seeded generator, plus normal deviates.
class Rng : public SplitMix64 {
 public:
  using SplitMix64::SplitMix64;
  double normal() {  ///< Box–Muller
    const double u = 1.0 - uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(6.283185307179586 * v);
  }
};

inline double frankeGradientNorm(double x, double y) {
  const double h = 1e-6;
  const double gx = (frankeFunction(x + h, y) - frankeFunction(x - h, y)) / (2 * h);
  const double gy = (frankeFunction(x, y + h) - frankeFunction(x, y - h)) / (2 * h);
  return std::hypot(gx, gy);
}

/// n points on [0, 1]², denser where Franke's function is steep (rejection
/// sampling with density ∝ 0.15 + |∇f| / max|∇f|), z = f + σ·N(0, 1).
inline std::vector<Point3> frankePoints(std::size_t n, std::uint64_t seed, double sigma = 0.0) {
  Rng rng(seed);
  double gmax = 0.0;
  for (int j = 0; j <= 100; ++j) {
    for (int i = 0; i <= 100; ++i) gmax = std::max(gmax, frankeGradientNorm(i / 100.0, j / 100.0));
  }
  std::vector<Point3> pts;
  pts.reserve(n);
  while (pts.size() < n) {
    const double x = rng.uniform(), y = rng.uniform();
    const double density = (0.15 + frankeGradientNorm(x, y) / gmax) / 1.15;
    if (rng.uniform() >= density) continue;
    const double noise = sigma > 0.0 ? sigma * rng.normal() : 0.0;
    pts.push_back({x, y, frankeFunction(x, y) + noise});
  }
  return pts;
}

/// A jittered n × n grid of squares over [0, 1]², each split by a diagonal
/// (alternating), triangles CCW.
struct SmallMesh {
  std::vector<Point2> vertices;
  std::vector<Triangle> triangles;
};

inline SmallMesh jitteredMesh(int n, std::uint64_t seed) {
  Rng rng(seed);
  SmallMesh m;
  const double h = 1.0 / n;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const bool inner = i > 0 && j > 0 && i < n && j < n;
      const double jx = inner ? (rng.uniform() - 0.5) * 0.4 * h : 0.0;
      const double jy = inner ? (rng.uniform() - 0.5) * 0.4 * h : 0.0;
      m.vertices.push_back({i * h + jx, j * h + jy});
    }
  }
  auto id = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        m.triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        m.triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  }
  return m;
}

/// Brute-force location: the first triangle whose barycentrics are all ≥ −1e-12.
inline Sample locateBruteForce(const SmallMesh& m, const Point3& p, double weight = 1.0) {
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    const auto b = barycentric(p.xy(), m.vertices[tri[0]], m.vertices[tri[1]], m.vertices[tri[2]]);
    if (b[0] >= -1e-12 && b[1] >= -1e-12 && b[2] >= -1e-12) return {static_cast<std::uint32_t>(t), b, p.z, weight};
  }
  return {0xffffffffu, {}, p.z, weight};
}

/// Checks that a triangulation of the square [x0, x0+size]² is conforming:
/// every triangle strictly CCW, every edge in one or two triangles with
/// opposite directions, edges with one triangle on the square's boundary, and
/// the areas summing to the square's. Returns "" or the first problem found.
inline std::string conformingSquareMesh(const std::vector<Point2>& v, const std::vector<Triangle>& tris, Point2 origin,
                                        double size) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  double area = 0.0;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const auto& tr = tris[t];
    const Point2 &a = v[tr[0]], &b = v[tr[1]], &c = v[tr[2]];
    const double a2 = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if (!(a2 > 0.0)) return "triangle " + std::to_string(t) + " is not CCW";
    area += 0.5 * a2;
    for (int k = 0; k < 3; ++k) {
      if (++directed[{tr[k], tr[(k + 1) % 3]}] > 1) return "directed edge used twice at triangle " + std::to_string(t);
    }
  }
  const double eps = 1e-12 * size;
  auto onBoundary = [&](const Point2& p, const Point2& q) {
    auto same = [&](double x, double y) { return std::abs(x - y) <= eps; };
    return (same(p.x, origin.x) && same(q.x, origin.x)) || (same(p.x, origin.x + size) && same(q.x, origin.x + size)) ||
           (same(p.y, origin.y) && same(q.y, origin.y)) || (same(p.y, origin.y + size) && same(q.y, origin.y + size));
  };
  for (const auto& [e, count] : directed) {
    if (directed.count({e.second, e.first}) == 0 && !onBoundary(v[e.first], v[e.second])) {
      return "interior edge (" + std::to_string(e.first) + ", " + std::to_string(e.second) + ") has one triangle (a crack)";
    }
  }
  if (std::abs(area - size * size) > 1e-9 * size * size) return "area " + std::to_string(area) + " is not the square's";
  return "";
}

}  // namespace tinsmith::fit::testing
