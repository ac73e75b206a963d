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
  const Rect extent = boundsOf(tin.vertices);
  // About four triangles a cell.
  const double cell = CellGrid::cellFor(extent.width(), extent.height(),
                                        std::max<std::size_t>(1, tin.triangles.size() / 4), 1e-9);
  grid_.emplace(extent.x0, extent.y0, extent.x1, extent.y1, cell);
  grid_->build(tin.triangles.size(), [&](std::size_t t, auto&& emit) {
    const Rect b = triangleBox(static_cast<std::uint32_t>(t));
    grid_->forEachCellOfBox(b.x0, b.y0, b.x1, b.y1, emit);
  });
}

Rect TinIndex::triangleBox(std::uint32_t t) const {
  const auto& tri = tin_.triangles[t];
  return boundsOf(std::array{tin_.vertices[tri[0]], tin_.vertices[tri[1]], tin_.vertices[tri[2]]});
}

void TinIndex::overlapping(const Rect& box, std::vector<std::uint32_t>& out) const {
  out.clear();
  if (!grid_) return;
  grid_->forEachInBox(box.x0, box.y0, box.x1, box.y1, [&](std::uint32_t t) {
    if (triangleBox(t).overlaps(box)) out.push_back(t);
  });
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
    index.overlapping(boundsOf(std::array{vertices[m[0]], vertices[m[1]], vertices[m[2]]}),
                      candidates);
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
