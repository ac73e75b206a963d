#include "core/tiles/surface_difference.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/geometry/predicates.hpp"

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
    const double det = geometry::orient2dInexact(a, b, c);
    inv = det != 0.0 ? 1.0 / det : 0.0;
  }
  [[nodiscard]] double at(P2 p) const {
    const double wb = geometry::orient2dInexact(a, p, c) * inv;
    const double wc = geometry::orient2dInexact(a, b, p) * inv;
    return za + wb * (zb - za) + wc * (zc - za);
  }
};

/// Which triangles a query has met, each once: an open-addressing set of
/// their ids (linear probing, at most half full), emptied by numbering the
/// queries (a slot counts in the query whose number it holds). Its size
/// follows the largest query (the triangles along one segment), not the
/// TIN: a mark per triangle, kept by every thread, held 4 bytes a triangle
/// per thread (8 GB a thread at 10^9 vertices).
class SeenSet {
 public:
  void begin() {
    count_ = 0;
    if (++query_ == 0) {  // wrapped: old slots could hold the new number
      std::fill(queries_.begin(), queries_.end(), 0);
      query_ = 1;
    }
  }
  /// True the first time `t` is met in this query.
  bool insert(std::uint32_t t) {
    if (2 * (count_ + 1) > ids_.size()) grow();
    for (std::size_t i = slotOf(t);; i = (i + 1) & (ids_.size() - 1)) {
      if (queries_[i] != query_) {
        queries_[i] = query_;
        ids_[i] = t;
        ++count_;
        return true;
      }
      if (ids_[i] == t) return false;
    }
  }

 private:
  [[nodiscard]] std::size_t slotOf(std::uint32_t t) const {  // Fibonacci hashing
    return static_cast<std::size_t>((t * 0x9E3779B97F4A7C15ULL) >> (64 - bits_));
  }
  void grow() {
    std::vector<std::uint32_t> ids = std::move(ids_), queries = std::move(queries_);
    bits_ = std::max(bits_ + 1, 6);
    ids_.assign(std::size_t{1} << bits_, 0);
    queries_.assign(ids_.size(), 0);
    count_ = 0;
    for (std::size_t i = 0; i < ids.size(); ++i)
      if (queries[i] == query_) insert(ids[i]);
  }

  std::vector<std::uint32_t> ids_, queries_;
  int bits_ = 0;
  std::size_t count_ = 0;
  std::uint32_t query_ = 0;
};

/// Inexact side test (the result is within rounding of the exact overlay,
/// which is all a bound on a difference needs).
double sideOf(P2 a, P2 b, P2 p) { return geometry::orient2dInexact(a, b, p); }

/// Whether the box [x0, x1] × [y0, y1] lies wholly right of one edge of the
/// counter-clockwise triangle c (then the two do not meet).
bool rightOfAnEdge(const std::array<P2, 3>& c, double x0, double y0, double x1, double y1) {
  const std::array<P2, 4> box{P2{x0, y0}, P2{x1, y0}, P2{x1, y1}, P2{x0, y1}};
  for (int i = 0; i < 3; ++i) {
    if (std::all_of(box.begin(), box.end(),
                    [&](const P2& q) { return sideOf(c[i], c[(i + 1) % 3], q) < 0; }))
      return true;
  }
  return false;
}

}  // namespace

TinIndex::TinIndex(const TinData& tin) : tin_(tin) {
  if (tin.vertices.empty() || tin.triangles.empty()) return;
  const Rect extent = boundsOf(tin.vertices);
  // About one triangle a cell for the triangles (a wall of contours 0.8 m
  // apart packs hundreds into a cell sized for four on average, and every
  // section along the wall went through them all), four for the vertices.
  const double cell = CellGrid::cellFor(extent.width(), extent.height(),
                                        std::max<std::size_t>(1, tin.triangles.size()), 1e-9);
  const double vertexCell = CellGrid::cellFor(
      extent.width(), extent.height(), std::max<std::size_t>(1, tin.triangles.size() / 4), 1e-9);
  grid_.emplace(extent.x0, extent.y0, extent.x1, extent.y1, cell);
  // A triangle is listed in the cells of its box that it comes within a
  // hundredth of a cell of, not in all of them: a contour TIN's slivers run
  // for kilometres at a slant (a mesa's plain and plateau between rings of
  // vertices 2 m apart), and listed by their boxes they filled every cell
  // with hundreds that no query there meets (740 candidates a section, 1 in
  // 44 crossed). The margin is far above the rounding of a query's cell walk
  // and of the clipping in section(), so every triangle a query can meet,
  // within rounding, is still listed in a cell the query visits.
  const double margin = 0.01 * cell;
  grid_->build(tin.triangles.size(), [&](std::size_t t, auto&& emit) {
    const Rect b = triangleBox(static_cast<std::uint32_t>(t));
    const auto& tri = tin.triangles[t];
    // Relative to the first corner, for precision at UTM-sized coordinates.
    const Point3& o = tin.vertices[tri[0]];
    const std::array<P2, 3> c{P2{0.0, 0.0},
                              P2{tin.vertices[tri[1]].x - o.x, tin.vertices[tri[1]].y - o.y},
                              P2{tin.vertices[tri[2]].x - o.x, tin.vertices[tri[2]].y - o.y}};
    // A degenerate triangle (not counter-clockwise) is kept in every cell.
    const bool ccw = sideOf(c[0], c[1], c[2]) > 0;
    // The cells of its box (as forEachCellOfBox), each kept unless it lies,
    // grown by the margin, wholly right of one of the triangle's edges.
    const auto cx0 = grid_->cellX(b.x0), cx1 = grid_->cellX(b.x1);
    const auto cy0 = grid_->cellY(b.y0), cy1 = grid_->cellY(b.y1);
    for (auto cy = cy0; cy <= cy1; ++cy) {
      for (auto cx = cx0; cx <= cx1; ++cx) {
        const double x0 = extent.x0 + static_cast<double>(cx) * cell - margin - o.x;
        const double y0 = extent.y0 + static_cast<double>(cy) * cell - margin - o.y;
        if (!ccw || !rightOfAnEdge(c, x0, y0, x0 + cell + 2 * margin, y0 + cell + 2 * margin))
          emit(grid_->index(cx, cy));
      }
    }
  });
  vertexGrid_.emplace(extent.x0, extent.y0, extent.x1, extent.y1, vertexCell);
  vertexGrid_->build(tin.vertices.size(), [&](std::size_t v, auto&& emit) {
    emit(vertexGrid_->index(vertexGrid_->cellX(tin.vertices[v].x),
                            vertexGrid_->cellY(tin.vertices[v].y)));
  });
}

void TinIndex::verticesIn(const Rect& box, std::vector<std::uint32_t>& out) const {
  out.clear();
  if (!vertexGrid_) return;
  vertexGrid_->forEachInBox(box.x0, box.y0, box.x1, box.y1, [&](std::uint32_t v) {
    if (box.contains(tin_.vertices[v].xy())) out.push_back(v);
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
    for (int i = 0; i < 3; ++i)
      c[i] = {tin_.vertices[tri[i]].x - p.x, tin_.vertices[tri[i]].y - p.y};
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
  // The triangles listed in the grid cells the segment passes through (the
  // box of a long diagonal segment holds far more), each once: a triangle
  // larger than a cell is listed in every cell it covers, and on a cliff's
  // contours beside a plain's that is hundreds (sorting the list to drop
  // them was a sixth of a tile job's time).
  thread_local SeenSet seen;
  seen.begin();
  std::vector<std::uint32_t> candidates;
  grid_->forEachCellOfSegment(a.x, a.y, b.x, b.y, [&](std::size_t c) {
    grid_->forEachInCell(c, [&](std::uint32_t t) {
      if (seen.insert(t)) candidates.push_back(t);
    });
  });
  // Each triangle's stretch of the segment, by clipping t ∈ [0, 1] to the
  // left of its three (CCW) edges; relative to a for precision.
  struct Stretch {
    double t0, t1, z0, z1;
    std::uint32_t triangle;
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
    stretches.push_back(
        {t0, t1, plane.at({t0 * d.x, t0 * d.y}), plane.at({t1 * d.x, t1 * d.y}), k});
  }
  // By t, ties by triangle id: the merge below keeps the lower id's z.
  std::sort(stretches.begin(), stretches.end(), [](const Stretch& x, const Stretch& y) {
    return x.t0 != y.t0 ? x.t0 < y.t0 : x.triangle < y.triangle;
  });
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

namespace {

EdgeDifference edgeDifference(Point3 p, Point3 q, const TinIndex& index,
                              std::vector<TinIndex::SectionPoint>& section) {
  if (q.x < p.x || (q.x == p.x && q.y < p.y)) std::swap(p, q);
  EdgeDifference r;
  index.section(p.xy(), q.xy(), section);
  for (const auto& sp : section) {
    if (std::isnan(sp.z)) continue;
    ++r.points;
    const double zm = p.z + sp.t * (q.z - p.z);
    const double d = std::abs(zm - sp.z);
    if (d > r.maxAbs) {
      r.maxAbs = d;
      r.at = {p.x + sp.t * (q.x - p.x), p.y + sp.t * (q.y - p.y)};
      r.meshZ = zm;
      r.tinZ = sp.z;
    }
  }
  return r;
}

}  // namespace

std::vector<SurfaceDifference> triangleDifferences(
    std::span<const Point3> vertices, std::span<const std::array<std::uint32_t, 3>> triangles,
    const TinIndex& index, EdgeDifferenceCache* cache) {
  std::vector<SurfaceDifference> result(triangles.size());
  if (triangles.empty()) return result;
  const TinData& tin = index.tin();
  std::vector<TinIndex::SectionPoint> section;
  std::vector<std::uint32_t> inside;
  if (cache && cache->generation_.size() < vertices.size())
    cache->generation_.resize(vertices.size(), 0);
  auto edge = [&](std::uint32_t a, std::uint32_t b) {
    if (!cache) return edgeDifference(vertices[a], vertices[b], index, section);
    const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
    const std::uint64_t key = (std::uint64_t{lo} << 32) | hi;
    const std::uint32_t ga = cache->generation_[lo], gb = cache->generation_[hi];
    auto [it, fresh] = cache->edges_.try_emplace(key);
    auto& entry = it->second;
    if (fresh || entry.generationA != ga || entry.generationB != gb) {
      entry = {edgeDifference(vertices[a], vertices[b], index, section), ga, gb};
    }
    return entry.difference;
  };
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const auto& m = triangles[i];
    SurfaceDifference& r = result[i];
    auto consider = [&](Point2 p, double zm, double zt) {
      const double d = std::abs(zm - zt);
      if (d > r.maxAbs) {
        r.maxAbs = d;
        r.at = p;
        r.meshZ = zm;
        r.tinZ = zt;
      }
      return d;
    };
    // The overlay's vertices on the triangle's edges: its corners (where the
    // TIN has them) and every crossing with a TIN edge, from the TIN's section
    // along each edge; the mesh is linear along it.
    for (int e = 0; e < 3; ++e) {
      const EdgeDifference d = edge(m[e], m[(e + 1) % 3]);
      r.pieces += d.points;
      consider(d.at, d.meshZ, d.tinZ);
    }
    // The TIN vertices inside, against the triangle's plane (relative to its
    // first corner: UTM-sized coordinates lose less).
    const P2 o{vertices[m[0]].x, vertices[m[0]].y};
    auto local = [&](const Point3& p) { return P2{p.x - o.x, p.y - o.y}; };
    const P2 a = local(vertices[m[0]]), b = local(vertices[m[1]]), c = local(vertices[m[2]]);
    const Plane plane(a, b, c, vertices[m[0]].z, vertices[m[1]].z, vertices[m[2]].z);
    index.verticesIn(boundsOf(std::array{vertices[m[0]], vertices[m[1]], vertices[m[2]]}), inside);
    for (std::uint32_t v : inside) {
      const P2 p = local(tin.vertices[v]);
      if (sideOf(a, b, p) < 0 || sideOf(b, c, p) < 0 || sideOf(c, a, p) < 0) continue;
      ++r.pieces;
      const double d = consider(tin.vertices[v].xy(), plane.at(p), tin.vertices[v].z);
      if (d > r.vertexAbs) {
        r.vertexAbs = d;
        r.vertex = tin.vertices[v].xy();
        r.vertexZ = tin.vertices[v].z;
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
