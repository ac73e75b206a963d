#include "core/tiles/surface_difference.hpp"

#include <algorithm>
#include <cmath>

namespace tinsmith::tiles {

namespace {

struct P2 {
  double x, y;
};

/// z of the plane through a triangle at p (barycentric, extrapolating).
struct Plane {
  P2 a, b, c;
  double za, zb, zc;
  double inv = 0.0;
  Plane(P2 a_, P2 b_, P2 c_, double za_, double zb_, double zc_)
      : a(a_), b(b_), c(c_), za(za_), zb(zb_), zc(zc_) {
    const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    inv = det != 0.0 ? 1.0 / det : 0.0;
  }
  [[nodiscard]] double at(P2 p) const {
    const double wb = ((p.x - a.x) * (c.y - a.y) - (c.x - a.x) * (p.y - a.y)) * inv;
    const double wc = ((b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y)) * inv;
    return za + wb * (zb - za) + wc * (zc - za);
  }
};

/// Inexact side test, used only to cut convex polygons (the result is within
/// rounding of the exact overlay, which is all a bound on a difference needs).
double sideOf(P2 a, P2 b, P2 p) {
  return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

/// Clips `poly` to the left half-plane of a → b.
void clipLeft(const std::vector<P2>& poly, P2 a, P2 b, std::vector<P2>& out) {
  out.clear();
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const P2 p = poly[i], q = poly[(i + 1) % n];
    const double sp = sideOf(a, b, p), sq = sideOf(a, b, q);
    if (sp >= 0) out.push_back(p);
    if ((sp > 0 && sq < 0) || (sp < 0 && sq > 0)) {
      const double t = sp / (sp - sq);
      out.push_back({p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)});
    }
  }
}

}  // namespace

TinIndex::TinIndex(const TinData& tin) : tin_(tin) {
  if (tin.vertices.empty() || tin.triangles.empty()) return;
  double x1 = -HUGE_VAL, y1 = -HUGE_VAL;
  x0_ = y0_ = HUGE_VAL;
  for (const auto& v : tin.vertices) {
    x0_ = std::min(x0_, v.x);
    y0_ = std::min(y0_, v.y);
    x1 = std::max(x1, v.x);
    y1 = std::max(y1, v.y);
  }
  const double area = std::max((x1 - x0_) * (y1 - y0_), 1e-300);
  cell_ = std::max(std::sqrt(area / static_cast<double>(tin.triangles.size())) * 2.0, 1e-9);
  nx_ = std::min<std::size_t>(static_cast<std::size_t>((x1 - x0_) / cell_) + 1, 1u << 14);
  ny_ = std::min<std::size_t>(static_cast<std::size_t>((y1 - y0_) / cell_) + 1, 1u << 14);
  cell_ = std::max((x1 - x0_) / static_cast<double>(nx_), (y1 - y0_) / static_cast<double>(ny_)) *
          (1 + 1e-12);
  if (cell_ <= 0) cell_ = 1;
  auto cellRange = [&](const std::array<std::uint32_t, 3>& t, std::size_t& i0, std::size_t& i1,
                       std::size_t& j0, std::size_t& j1) {
    double lx = HUGE_VAL, ly = HUGE_VAL, hx = -HUGE_VAL, hy = -HUGE_VAL;
    for (auto v : t) {
      lx = std::min(lx, tin.vertices[v].x);
      ly = std::min(ly, tin.vertices[v].y);
      hx = std::max(hx, tin.vertices[v].x);
      hy = std::max(hy, tin.vertices[v].y);
    }
    i0 = std::min(nx_ - 1, static_cast<std::size_t>(std::max(0.0, (lx - x0_) / cell_)));
    i1 = std::min(nx_ - 1, static_cast<std::size_t>(std::max(0.0, (hx - x0_) / cell_)));
    j0 = std::min(ny_ - 1, static_cast<std::size_t>(std::max(0.0, (ly - y0_) / cell_)));
    j1 = std::min(ny_ - 1, static_cast<std::size_t>(std::max(0.0, (hy - y0_) / cell_)));
  };
  begin_.assign(nx_ * ny_ + 1, 0);
  for (const auto& t : tin.triangles) {
    std::size_t i0, i1, j0, j1;
    cellRange(t, i0, i1, j0, j1);
    for (std::size_t j = j0; j <= j1; ++j)
      for (std::size_t i = i0; i <= i1; ++i) ++begin_[j * nx_ + i + 1];
  }
  for (std::size_t c = 0; c < nx_ * ny_; ++c) begin_[c + 1] += begin_[c];
  items_.resize(begin_.back());
  std::vector<std::uint32_t> fill(begin_.begin(), begin_.end() - 1);
  for (std::uint32_t k = 0; k < tin.triangles.size(); ++k) {
    std::size_t i0, i1, j0, j1;
    cellRange(tin.triangles[k], i0, i1, j0, j1);
    for (std::size_t j = j0; j <= j1; ++j)
      for (std::size_t i = i0; i <= i1; ++i) items_[fill[j * nx_ + i]++] = k;
  }
}

void TinIndex::overlapping(const Rect& box, std::vector<std::uint32_t>& out) const {
  out.clear();
  if (items_.empty()) return;
  auto clampCell = [](double v, std::size_t n) {
    return static_cast<std::size_t>(std::clamp(v, 0.0, static_cast<double>(n - 1)));
  };
  const std::size_t i0 = clampCell((box.x0 - x0_) / cell_, nx_),
                    i1 = clampCell((box.x1 - x0_) / cell_, nx_);
  const std::size_t j0 = clampCell((box.y0 - y0_) / cell_, ny_),
                    j1 = clampCell((box.y1 - y0_) / cell_, ny_);
  for (std::size_t j = j0; j <= j1; ++j) {
    for (std::size_t i = i0; i <= i1; ++i) {
      const std::size_t c = j * nx_ + i;
      for (std::uint32_t k = begin_[c]; k < begin_[c + 1]; ++k) {
        const auto& t = tin_.triangles[items_[k]];
        double lx = HUGE_VAL, ly = HUGE_VAL, hx = -HUGE_VAL, hy = -HUGE_VAL;
        for (auto v : t) {
          lx = std::min(lx, tin_.vertices[v].x);
          ly = std::min(ly, tin_.vertices[v].y);
          hx = std::max(hx, tin_.vertices[v].x);
          hy = std::max(hy, tin_.vertices[v].y);
        }
        if (hx < box.x0 || lx > box.x1 || hy < box.y0 || ly > box.y1) continue;
        out.push_back(items_[k]);
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

SurfaceDifference maxVerticalDifference(std::span<const Point3> vertices,
                                        std::span<const std::array<std::uint32_t, 3>> triangles,
                                        const TinIndex& index) {
  SurfaceDifference result;
  if (triangles.empty()) return result;
  const TinData& tin = index.tin();
  // Work relative to the first vertex: UTM-sized coordinates lose less.
  const double ox = vertices[triangles[0][0]].x, oy = vertices[triangles[0][0]].y;
  auto local = [&](const Point3& p) { return P2{p.x - ox, p.y - oy}; };
  std::vector<std::uint32_t> candidates;
  std::vector<P2> poly, next;
  for (const auto& m : triangles) {
    const P2 a = local(vertices[m[0]]), b = local(vertices[m[1]]), c = local(vertices[m[2]]);
    const Plane meshPlane(a, b, c, vertices[m[0]].z, vertices[m[1]].z, vertices[m[2]].z);
    Rect box{std::min({a.x, b.x, c.x}) + ox, std::min({a.y, b.y, c.y}) + oy,
             std::max({a.x, b.x, c.x}) + ox, std::max({a.y, b.y, c.y}) + oy};
    index.overlapping(box, candidates);
    for (std::uint32_t k : candidates) {
      const auto& t = tin.triangles[k];
      const P2 ta = local(tin.vertices[t[0]]), tb = local(tin.vertices[t[1]]),
               tc = local(tin.vertices[t[2]]);
      poly = {ta, tb, tc};
      clipLeft(poly, a, b, next);
      clipLeft(next, b, c, poly);
      clipLeft(poly, c, a, next);
      if (next.empty()) continue;
      const Plane tinPlane(ta, tb, tc, tin.vertices[t[0]].z, tin.vertices[t[1]].z,
                           tin.vertices[t[2]].z);
      ++result.pieces;
      for (const P2& p : next) {
        const double zm = meshPlane.at(p), zt = tinPlane.at(p);
        const double d = std::abs(zm - zt);
        if (d > result.maxAbs) {
          result.maxAbs = d;
          result.at = {p.x + ox, p.y + oy};
          result.meshZ = zm;
          result.tinZ = zt;
        }
      }
    }
  }
  return result;
}

}  // namespace tinsmith::tiles
