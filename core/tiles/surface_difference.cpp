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

std::optional<double> TinIndex::z(Point2 p) const {
  std::vector<std::uint32_t> candidates;
  overlapping({p.x, p.y, p.x, p.y}, candidates);
  for (std::uint32_t k : candidates) {
    const auto& tri = tin_.triangles[k];
    std::array<P2, 3> c{};
    for (int i = 0; i < 3; ++i) c[i] = {tin_.vertices[tri[i]].x - p.x, tin_.vertices[tri[i]].y - p.y};
    bool inside = true;
    for (int i = 0; i < 3 && inside; ++i) inside = sideOf(c[i], c[(i + 1) % 3], {0.0, 0.0}) >= 0;
    if (!inside) continue;
    return Plane(c[0], c[1], c[2], tin_.vertices[tri[0]].z, tin_.vertices[tri[1]].z,
                 tin_.vertices[tri[2]].z)
        .at({0.0, 0.0});
  }
  return std::nullopt;
}

void TinIndex::section(Point2 a, Point2 b, std::vector<SectionPoint>& out) const {
  out.clear();
  if (!grid_) return;
  std::vector<std::uint32_t> candidates;
  overlapping(boundsOf(std::array{a, b}), candidates);
  // Each triangle's stretch of the segment, by clipping t ∈ [0, 1] to the
  // left of its three (CCW) edges; relative to a for precision.
  struct Stretch {
    double t0, t1, z0, z1;
  };
  std::vector<Stretch> stretches;
  const P2 d{b.x - a.x, b.y - a.y};
  for (std::uint32_t k : candidates) {
    const auto& tri = tin_.triangles[k];
    std::array<P2, 3> c{};
    for (int i = 0; i < 3; ++i) {
      c[i] = {tin_.vertices[tri[i]].x - a.x, tin_.vertices[tri[i]].y - a.y};
    }
    double t0 = 0.0, t1 = 1.0;
    for (int i = 0; i < 3 && t0 <= t1; ++i) {
      const P2 p = c[i], q = c[(i + 1) % 3];
      // side(t) = s0 + t·ds ≥ 0 inside.
      const double s0 = sideOf(p, q, {0.0, 0.0});
      const double ds = (q.x - p.x) * d.y - (q.y - p.y) * d.x;
      if (ds == 0.0) {
        if (s0 < 0) t1 = -1.0;
      } else if (ds > 0) {
        t0 = std::max(t0, -s0 / ds);
      } else {
        t1 = std::min(t1, -s0 / ds);
      }
    }
    if (t0 > t1) continue;
    const Plane plane(c[0], c[1], c[2], tin_.vertices[tri[0]].z, tin_.vertices[tri[1]].z,
                      tin_.vertices[tri[2]].z);
    stretches.push_back({t0, t1, plane.at({t0 * d.x, t0 * d.y}), plane.at({t1 * d.x, t1 * d.y})});
  }
  std::stable_sort(stretches.begin(), stretches.end(),
                   [](const Stretch& x, const Stretch& y) { return x.t0 < y.t0; });
  constexpr double kMerge = 1e-12;
  double reach = -1.0;
  auto push = [&](double t, double z) {
    if (!out.empty() && t <= out.back().t + kMerge) return;
    out.push_back({t, z});
  };
  for (const Stretch& s : stretches) {
    if (!out.empty() && s.t0 > reach + kMerge) out.push_back({reach, std::nan("")});
    push(s.t0, s.z0);
    push(s.t1, s.z1);
    reach = std::max(reach, s.t1);
  }
}

std::vector<SurfaceDifference> triangleDifferences(
    std::span<const Point3> vertices, std::span<const std::array<std::uint32_t, 3>> triangles,
    const TinIndex& index) {
  std::vector<SurfaceDifference> result(triangles.size());
  if (triangles.empty()) return result;
  const TinData& tin = index.tin();
  // Work relative to the first vertex: UTM-sized coordinates lose less.
  const double ox = vertices[triangles[0][0]].x, oy = vertices[triangles[0][0]].y;
  auto local = [&](const Point3& p) { return P2{p.x - ox, p.y - oy}; };
  std::vector<std::uint32_t> candidates;
  std::vector<P2> poly, next;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const auto& m = triangles[i];
    SurfaceDifference& r = result[i];
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
      ++r.pieces;
      for (const P2& p : next) {
        const double zm = meshPlane.at(p), zt = tinPlane.at(p);
        const double d = std::abs(zm - zt);
        if (d > r.maxAbs) {
          r.maxAbs = d;
          r.at = {p.x + ox, p.y + oy};
          r.meshZ = zm;
          r.tinZ = zt;
          r.tinTriangle = k;
        }
        // Clipping keeps a TIN corner inside the mesh triangle bit for bit.
        for (int i = 0; i < 3; ++i) {
          const P2 corner = i == 0 ? ta : i == 1 ? tb : tc;
          if (p.x == corner.x && p.y == corner.y && d > r.vertexAbs) {
            r.vertexAbs = d;
            r.vertex = {tin.vertices[t[i]].x, tin.vertices[t[i]].y};
            r.vertexZ = tin.vertices[t[i]].z;
          }
        }
      }
    }
  }
  return result;
}

SurfaceDifference maxVerticalDifference(std::span<const Point3> vertices,
                                        std::span<const std::array<std::uint32_t, 3>> triangles,
                                        const TinIndex& index) {
  SurfaceDifference result;
  for (const SurfaceDifference& d : triangleDifferences(vertices, triangles, index)) {
    result.pieces += d.pieces;
    if (d.maxAbs > result.maxAbs) {
      const std::size_t pieces = result.pieces;
      result = d;
      result.pieces = pieces;
    }
  }
  return result;
}

}  // namespace tinsmith::tiles
