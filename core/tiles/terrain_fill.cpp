#include "core/tiles/terrain_fill.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "core/base/error.hpp"
#include "core/cdt/cdt.hpp"
#include "core/tiles/geographic_grid.hpp"

namespace tinsmith::tiles {

namespace {

using Edge = std::pair<std::uint32_t, std::uint32_t>;

/// The surface's boundary: its directed edges whose reverse no triangle
/// has (the surface on their left).
std::vector<Edge> boundaryEdges(const TileSurface& s) {
  std::vector<std::uint64_t> directed;
  directed.reserve(3 * s.triangles.size());
  for (const auto& t : s.triangles)
    for (int i = 0; i < 3; ++i) directed.push_back(std::uint64_t{t[i]} << 32 | t[(i + 1) % 3]);
  std::sort(directed.begin(), directed.end());
  std::vector<Edge> out;
  for (const std::uint64_t e : directed) {
    const std::uint64_t reverse = (e & 0xffffffffU) << 32 | e >> 32;
    if (!std::binary_search(directed.begin(), directed.end(), reverse))
      out.emplace_back(static_cast<std::uint32_t>(e >> 32), static_cast<std::uint32_t>(e));
  }
  return out;
}

double distanceToSegment(Point2 p, Point2 a, Point2 b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double l2 = dx * dx + dy * dy;
  const double t = l2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / l2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy));
}

}  // namespace

int fillSegmentsForLevel(int level) {
  // A cell α radians a side splits into two right triangles whose chord sags
  // (hypotenuse)² / 8R = α²R / 4 at most on a sphere of the largest radius;
  // R(1 − cos) is below it. Within a quarter of the level's error.
  constexpr double kR = 6378137.0;
  const double side = std::numbers::pi * std::ldexp(1.0, -level);
  const double alpha = std::sqrt(cesiumLevelMaximumGeometricError(level) / kR);
  int n = 1;
  while (side / n > alpha && n < (1 << 12)) n *= 2;
  return n;
}

TerrainFill fillOutsideSurface(const TileSurface& surface, const Rect& rect, int segments) {
  if (segments < 1) throw internalError("fillOutsideSurface: segments must be at least 1");
  const auto n = static_cast<std::uint32_t>(segments);
  const auto S = static_cast<std::uint32_t>(surface.vertices.size());
  const std::vector<Edge> boundary = boundaryEdges(surface);
  const auto onSide = [&](const Edge& e) {
    return (surface.flags[e.first] & surface.flags[e.second] & 15) != 0;
  };
  TerrainFill fill;
  if (!surface.empty() && std::all_of(boundary.begin(), boundary.end(), onSide))
    return fill;  // a surface bounded by the sides alone is the whole rectangle

  // Grid coordinates from the rectangle's own sides: the neighbour sharing
  // a side computes the same doubles along it.
  const auto gx = [&](std::uint32_t i) {
    return i == n ? rect.x1 : rect.x0 + (rect.x1 - rect.x0) * (static_cast<double>(i) / n);
  };
  const auto gy = [&](std::uint32_t j) {
    return j == n ? rect.y1 : rect.y0 + (rect.y1 - rect.y0) * (static_cast<double>(j) / n);
  };
  // The boundary edges by grid cell, to keep grid points off them: a point
  // on a constraint would split it, and the wall above would not meet the
  // fill's edge there.
  const double near = 1e-6 * std::max(rect.width(), rect.height());
  std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(n) * n);
  const auto cellOf = [&](double v, double lo, double hi) {
    return static_cast<std::uint32_t>(
        std::clamp(std::floor((v - lo) / (hi - lo) * n), 0.0, static_cast<double>(n - 1)));
  };
  for (std::uint32_t k = 0; k < boundary.size(); ++k) {
    const Point3 &a = surface.vertices[boundary[k].first], &b = surface.vertices[boundary[k].second];
    const std::uint32_t i0 = cellOf(std::min(a.x, b.x) - near, rect.x0, rect.x1),
                        i1 = cellOf(std::max(a.x, b.x) + near, rect.x0, rect.x1),
                        j0 = cellOf(std::min(a.y, b.y) - near, rect.y0, rect.y1),
                        j1 = cellOf(std::max(a.y, b.y) + near, rect.y0, rect.y1);
    for (std::uint32_t j = j0; j <= j1; ++j)
      for (std::uint32_t i = i0; i <= i1; ++i) cells[j * n + i].push_back(k);
  }
  const auto clearOfBoundary = [&](std::uint32_t i, std::uint32_t j) {
    const Point2 p{gx(i), gy(j)};
    for (std::uint32_t cj = j == 0 ? 0 : j - 1; cj <= std::min(j, n - 1); ++cj) {
      for (std::uint32_t ci = i == 0 ? 0 : i - 1; ci <= std::min(i, n - 1); ++ci) {
        for (const std::uint32_t k : cells[cj * n + ci]) {
          const Point3 &a = surface.vertices[boundary[k].first],
                       &b = surface.vertices[boundary[k].second];
          if (distanceToSegment(p, a.xy(), b.xy()) <= near) return false;
        }
      }
    }
    return true;
  };

  // Grid points, then the boundary rings (the surface's footprint, as holes).
  std::vector<Point3> points;
  for (std::uint32_t j = 0; j <= n; ++j)
    for (std::uint32_t i = 0; i <= n; ++i)
      if (clearOfBoundary(i, j)) points.push_back({gx(i), gy(j), 0.0});
  for (const Point2 c : {Point2{rect.x0, rect.y0}, Point2{rect.x1, rect.y0},
                         Point2{rect.x1, rect.y1}, Point2{rect.x0, rect.y1}}) {
    // A corner the surface covers is in its rings; one it does not must be
    // a point for the fill to reach it.
    if (std::none_of(points.begin(), points.end(),
                     [&](const Point3& p) { return p.x == c.x && p.y == c.y; }))
      points.push_back({c.x, c.y, 0.0});
  }

  Cdt cdt;
  const FeatureId hole = cdt.addFeature(FeatureKind::Hole, "the TIN's footprint in the tile");
  cdt.insertPoints(points, kNoFeature);
  std::vector<VertexId> input(S, VertexId::invalid());  // a surface vertex's input vertex
  {
    std::multimap<std::uint32_t, std::size_t> from;  // start vertex → boundary edge
    for (std::size_t k = 0; k < boundary.size(); ++k) from.emplace(boundary[k].first, k);
    std::vector<bool> used(boundary.size(), false);
    std::vector<Point3> ring;
    std::vector<std::uint32_t> ringVertices;
    for (std::size_t start = 0; start < boundary.size(); ++start) {
      if (used[start]) continue;
      ring.clear();
      ringVertices.clear();
      std::size_t k = start;
      while (!used[k]) {
        used[k] = true;
        ringVertices.push_back(boundary[k].first);
        const Point3& p = surface.vertices[boundary[k].first];
        ring.push_back({p.x, p.y, 0.0});
        const std::uint32_t next = boundary[k].second;
        auto [lo, hi] = from.equal_range(next);
        auto it = std::find_if(lo, hi, [&](const auto& e) { return !used[e.second]; });
        if (it == hi) {
          if (next != boundary[start].first)
            throw internalError("fillOutsideSurface: the boundary of tile " + surface.id.name() +
                                " does not close");
          break;
        }
        k = it->second;
      }
      const VertexId first{static_cast<std::uint32_t>(cdt.inputVertexCount())};
      cdt.addHole(ring, hole);
      for (std::size_t r = 0; r < ringVertices.size(); ++r) {
        if (!input[ringVertices[r]].valid())
          input[ringVertices[r]] = VertexId{first.value + static_cast<std::uint32_t>(r)};
      }
    }
  }
  cdt.finalize();
  const TinData mesh = cdt.toTinData();
  fill.vertices = mesh.vertices;
  for (auto& v : fill.vertices) v.z = 0.0;
  for (const auto& t : mesh.triangles) fill.triangles.push_back({S + t[0], S + t[1], S + t[2]});
  for (const Edge& e : boundary) {
    if (onSide(e)) continue;
    const VertexId a0 = cdt.meshVertex(input[e.first]), b0 = cdt.meshVertex(input[e.second]);
    if (!a0.valid() || !b0.valid())
      throw internalError("fillOutsideSurface: a boundary vertex of tile " + surface.id.name() +
                          " is not in its fill");
    fill.walls.push_back({S + a0.value, S + b0.value, e.second});
    fill.walls.push_back({S + a0.value, e.second, e.first});
  }
  return fill;
}

}  // namespace tinsmith::tiles
