// Surface queries over a Mesh (see surface.hpp).
#include "core/surface/surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/geometry/predicates.hpp"

namespace tinsmith {

Surface::Surface(const TinData& tin) : Surface(Mesh::fromTinData(tin)) {}

Surface::Surface(Mesh mesh) : mesh_(std::move(mesh)) {
  const std::size_t nt = mesh_.triangleCount();
  if (nt == 0) return;
  double maxX = -INFINITY, maxY = -INFINITY;
  minX_ = INFINITY;
  minY_ = INFINITY;
  for (std::uint32_t t = 0; t < nt; ++t) {
    for (VertexId v : mesh_.vertices(TriangleId(t))) {
      const Point3& p = mesh_.point(v);
      minX_ = std::min(minX_, p.x);
      minY_ = std::min(minY_, p.y);
      maxX = std::max(maxX, p.x);
      maxY = std::max(maxY, p.y);
    }
  }
  const double w = std::max(maxX - minX_, 1e-300), h = std::max(maxY - minY_, 1e-300);
  // About two triangles per cell.
  const double cells = std::max(1.0, static_cast<double>(nt) / 2.0);
  const double side = std::sqrt(w * h / cells);
  cellsX_ = static_cast<std::size_t>(std::clamp(std::ceil(w / side), 1.0, 4096.0));
  cellsY_ = static_cast<std::size_t>(std::clamp(std::ceil(h / side), 1.0, 4096.0));
  cellW_ = w / static_cast<double>(cellsX_);
  cellH_ = h / static_cast<double>(cellsY_);

  auto cellRange = [&](std::uint32_t t, std::size_t& x0, std::size_t& x1, std::size_t& y0,
                       std::size_t& y1) {
    double lx = INFINITY, ly = INFINITY, hx = -INFINITY, hy = -INFINITY;
    for (VertexId v : mesh_.vertices(TriangleId(t))) {
      const Point3& p = mesh_.point(v);
      lx = std::min(lx, p.x);
      ly = std::min(ly, p.y);
      hx = std::max(hx, p.x);
      hy = std::max(hy, p.y);
    }
    auto cx = [&](double x) {
      return static_cast<std::size_t>(
          std::clamp(std::floor((x - minX_) / cellW_), 0.0, static_cast<double>(cellsX_ - 1)));
    };
    auto cy = [&](double y) {
      return static_cast<std::size_t>(
          std::clamp(std::floor((y - minY_) / cellH_), 0.0, static_cast<double>(cellsY_ - 1)));
    };
    x0 = cx(lx);
    x1 = cx(hx);
    y0 = cy(ly);
    y1 = cy(hy);
  };
  cellBegin_.assign(cellsX_ * cellsY_ + 1, 0);
  for (std::uint32_t t = 0; t < nt; ++t) {
    std::size_t x0, x1, y0, y1;
    cellRange(t, x0, x1, y0, y1);
    for (std::size_t y = y0; y <= y1; ++y) {
      for (std::size_t x = x0; x <= x1; ++x) ++cellBegin_[y * cellsX_ + x + 1];
    }
  }
  for (std::size_t i = 0; i + 1 < cellBegin_.size(); ++i) cellBegin_[i + 1] += cellBegin_[i];
  cellTriangles_.resize(cellBegin_.back());
  std::vector<std::uint32_t> fill(cellBegin_.begin(), cellBegin_.end() - 1);
  for (std::uint32_t t = 0; t < nt; ++t) {
    std::size_t x0, x1, y0, y1;
    cellRange(t, x0, x1, y0, y1);
    for (std::size_t y = y0; y <= y1; ++y) {
      for (std::size_t x = x0; x <= x1; ++x) cellTriangles_[fill[y * cellsX_ + x]++] = t;
    }
  }
}

bool Surface::contains(TriangleId t, Point2 p) const {
  const auto v = mesh_.vertices(t);
  for (int i = 0; i < 3; ++i) {
    if (geometry::orient2d(mesh_.xy(v[i]), mesh_.xy(v[(i + 1) % 3]), p) < 0) return false;
  }
  return true;
}

SurfaceLocation Surface::weightsIn(TriangleId t, Point2 p) const {
  const auto v = mesh_.vertices(t);
  const Point2 a = mesh_.xy(v[0]), b = mesh_.xy(v[1]), c = mesh_.xy(v[2]);
  // Relative coordinates keep UTM-sized values exact enough.
  const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
  const double px = p.x - a.x, py = p.y - a.y;
  const double area = bx * cy - by * cx;
  SurfaceLocation loc;
  loc.triangle = t;
  const double w1 = (px * cy - py * cx) / area;
  const double w2 = (bx * py - by * px) / area;
  loc.weights = {1.0 - w1 - w2, w1, w2};
  return loc;
}

std::optional<SurfaceLocation> Surface::locate(Point2 p, TriangleId hint) const {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || mesh_.triangleCount() == 0) {
    return std::nullopt;
  }
  if (hint.valid() && hint.value < mesh_.triangleCount()) {
    TriangleId t = hint;
    for (int steps = 0; steps < 64; ++steps) {
      bool moved = false;
      const auto v = mesh_.vertices(t);
      for (int i = 0; i < 3; ++i) {
        if (geometry::orient2d(mesh_.xy(v[i]), mesh_.xy(v[(i + 1) % 3]), p) < 0) {
          const HalfedgeId tw = mesh_.twin(Mesh::halfedge(t, i));
          if (tw.valid()) {
            t = Mesh::triangle(tw);
            moved = true;
          }
          break;
        }
      }
      if (!moved) {
        if (contains(t, p)) return weightsIn(t, p);
        break;
      }
    }
  }
  const double fx = std::floor((p.x - minX_) / cellW_), fy = std::floor((p.y - minY_) / cellH_);
  if (fx < 0 || fy < 0 || fx >= static_cast<double>(cellsX_) + 1 ||
      fy >= static_cast<double>(cellsY_) + 1) {
    return std::nullopt;
  }
  const auto cx = std::min(static_cast<std::size_t>(fx), cellsX_ - 1);
  const auto cy = std::min(static_cast<std::size_t>(fy), cellsY_ - 1);
  const std::size_t cell = cy * cellsX_ + cx;
  for (std::uint32_t i = cellBegin_[cell]; i < cellBegin_[cell + 1]; ++i) {
    const TriangleId t(cellTriangles_[i]);
    if (contains(t, p)) return weightsIn(t, p);
  }
  return std::nullopt;
}

std::optional<double> Surface::z(Point2 p) const {
  const auto loc = locate(p);
  if (!loc) return std::nullopt;
  const auto v = mesh_.vertices(loc->triangle);
  return loc->weights[0] * mesh_.z(v[0]) + loc->weights[1] * mesh_.z(v[1]) +
         loc->weights[2] * mesh_.z(v[2]);
}

std::optional<SurfaceSample> Surface::sample(Point2 p) const {
  const auto loc = locate(p);
  if (!loc) return std::nullopt;
  const auto v = mesh_.vertices(loc->triangle);
  const Point3 &a = mesh_.point(v[0]), &b = mesh_.point(v[1]), &c = mesh_.point(v[2]);
  SurfaceSample s;
  s.triangle = loc->triangle;
  s.z = loc->weights[0] * a.z + loc->weights[1] * b.z + loc->weights[2] * c.z;
  const double ex = b.x - a.x, ey = b.y - a.y, ez = b.z - a.z;
  const double fx = c.x - a.x, fy = c.y - a.y, fz = c.z - a.z;
  const double nx = ey * fz - ez * fy, ny = ez * fx - ex * fz, nz = ex * fy - ey * fx;
  const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
  s.normal = {nx / len, ny / len, nz / len};
  s.slope = std::hypot(nx, ny) / nz;
  s.slopeDegrees = std::atan(s.slope) * 180.0 / std::numbers::pi;
  return s;
}

std::vector<double> Surface::zMany(std::span<const Point2> points) const {
  std::vector<double> out(points.size(), std::numeric_limits<double>::quiet_NaN());
  TriangleId hint;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto loc = locate(points[i], hint);
    if (!loc) continue;
    hint = loc->triangle;
    const auto v = mesh_.vertices(loc->triangle);
    out[i] = loc->weights[0] * mesh_.z(v[0]) + loc->weights[1] * mesh_.z(v[1]) +
             loc->weights[2] * mesh_.z(v[2]);
  }
  return out;
}

std::vector<double> Surface::zGrid(const SampleGrid& g) const {
  std::vector<Point2> pts;
  pts.reserve(g.nx * g.ny);
  for (std::size_t j = 0; j < g.ny; ++j) {
    for (std::size_t i = 0; i < g.nx; ++i) {
      pts.push_back({g.x0 + static_cast<double>(i) * g.dx, g.y0 + static_cast<double>(j) * g.dy});
    }
  }
  return zMany(pts);
}

std::vector<std::uint32_t> Surface::trianglesNearSegment(Point2 a, Point2 b) const {
  std::vector<std::uint32_t> out;
  if (mesh_.triangleCount() == 0) return out;
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  const double step = 0.5 * std::min(cellW_, cellH_);
  const auto n = static_cast<std::size_t>(std::min(1e7, std::ceil(len / step))) + 1;
  std::vector<std::size_t> cells;
  for (std::size_t k = 0; k <= n; ++k) {
    const double s = static_cast<double>(k) / static_cast<double>(n);
    const double x = a.x + s * (b.x - a.x), y = a.y + s * (b.y - a.y);
    const double fx = std::floor((x - minX_) / cellW_), fy = std::floor((y - minY_) / cellH_);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const double cx = fx + dx, cy = fy + dy;
        if (cx < 0 || cy < 0 || cx >= static_cast<double>(cellsX_) ||
            cy >= static_cast<double>(cellsY_)) {
          continue;
        }
        cells.push_back(static_cast<std::size_t>(cy) * cellsX_ + static_cast<std::size_t>(cx));
      }
    }
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  for (std::size_t c : cells) {
    out.insert(out.end(), cellTriangles_.begin() + cellBegin_[c],
               cellTriangles_.begin() + cellBegin_[c + 1]);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<ProfilePoint> Surface::profile(std::span<const Point2> polyline) const {
  std::vector<ProfilePoint> out;
  double base = 0;
  TriangleId hint;
  for (std::size_t s = 0; s + 1 < polyline.size() || (s == 0 && polyline.size() == 1); ++s) {
    const Point2 a = polyline[s];
    const Point2 b = polyline.size() == 1 ? a : polyline[s + 1];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    std::vector<double> params{0.0, 1.0};
    if (len > 0) {
      for (std::uint32_t t : trianglesNearSegment(a, b)) {
        const auto v = mesh_.vertices(TriangleId(t));
        for (int i = 0; i < 3; ++i) {
          const Point2 p = mesh_.xy(v[i]), q = mesh_.xy(v[(i + 1) % 3]);
          const auto kind = geometry::segmentIntersection(a, b, p, q);
          if (kind == geometry::SegmentIntersection::Proper) {
            const Point2 x = geometry::intersectionPoint(a, b, p, q);
            params.push_back(((x.x - a.x) * (b.x - a.x) + (x.y - a.y) * (b.y - a.y)) /
                             (len * len));
          } else if (kind != geometry::SegmentIntersection::None) {
            for (const Point2& e : {p, q}) {
              if (geometry::onSegment(a, b, e)) {
                params.push_back(((e.x - a.x) * (b.x - a.x) + (e.y - a.y) * (b.y - a.y)) /
                                 (len * len));
              }
            }
          }
        }
      }
    }
    for (double& t : params) t = std::clamp(t, 0.0, 1.0);
    std::sort(params.begin(), params.end());
    std::vector<double> ts;
    for (double t : params) {
      if (!ts.empty() && (t - ts.back()) * std::max(len, 1.0) <= 1e-12 * std::max(len, 1.0)) {
        continue;
      }
      ts.push_back(t);
    }
    auto emit = [&](double t) {
      ProfilePoint pp;
      pp.distance = base + t * len;
      pp.point = {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y),
                  std::numeric_limits<double>::quiet_NaN()};
      if (t == 1.0) pp.point = {b.x, b.y, pp.point.z};
      const auto loc = locate(pp.point.xy(), hint);
      if (loc) {
        hint = loc->triangle;
        const auto v = mesh_.vertices(loc->triangle);
        pp.point.z = loc->weights[0] * mesh_.z(v[0]) + loc->weights[1] * mesh_.z(v[1]) +
                     loc->weights[2] * mesh_.z(v[2]);
        pp.inside = true;
      }
      out.push_back(pp);
    };
    for (std::size_t k = 0; k < ts.size(); ++k) {
      // The start of a segment repeats the previous segment's end.
      if (!(k == 0 && s > 0)) emit(ts[k]);
      if (k + 1 < ts.size()) {
        // Between two crossings the surface is linear — unless there is a gap
        // (hole, outside); a midpoint sample marks it.
        const double mid = 0.5 * (ts[k] + ts[k + 1]);
        const Point2 m{a.x + mid * (b.x - a.x), a.y + mid * (b.y - a.y)};
        if (!locate(m, hint)) emit(mid);
      }
    }
    base += len;
    if (polyline.size() == 1) break;
  }
  return out;
}

}  // namespace tinsmith
