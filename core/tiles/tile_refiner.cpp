#include "core/tiles/tile_refiner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>

#include "core/geometry/predicates.hpp"
#include "core/mesh/mesh.hpp"

namespace tinsmith::tiles {

namespace {

using geometry::incircle;
using geometry::orient2d;

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

/// What an edge is, for what may happen to it.
enum class EdgeKind : std::uint8_t {
  Free,   ///< may be flipped or split
  Line,   ///< a break line or ring: split, never flipped
  River,  ///< a Line whose new vertex keeps its z between the edge's ends
  Side,   ///< a tile side: neither
};

class Refiner {
 public:
  Refiner(TileSurface& tile, const TinIndex& tin, const RefineOptions& options)
      : tile_(tile),
        tri_(tile.triangles),
        tin_(tin),
        options_(options),
        diff_(triangleDifferences(tile.vertices, tile.triangles, tin, &edges_)) {
    const std::size_t nt = tri_.size();
    twin_.assign(3 * nt, kNone);
    kind_.assign(3 * nt, EdgeKind::Free);
    version_.assign(nt, 0);
    outOfReach_.assign(nt, 0);
    vout_.assign(tile_.vertices.size(), kNone);
    // The twins from the project's mesh (half-edge 3t + i runs from corner i
    // to corner i + 1 there too); from here on the refiner keeps them.
    TinData shape;
    shape.vertices = tile_.vertices;
    shape.triangles.assign(tri_.begin(), tri_.end());
    const Mesh mesh = Mesh::fromTinData(shape);
    for (std::uint32_t h = 0; h < 3 * nt; ++h) {
      const HalfedgeId g = mesh.twin(HalfedgeId(h));
      if (g.valid()) twin_[h] = g.value;
      vout_[tri_[h / 3][h % 3]] = h;
    }
    for (std::uint32_t h = 0; h < 3 * nt; ++h) {
      const std::uint32_t t = h / 3, i = h % 3;
      const std::uint32_t a = tri_[t][i], b = tri_[t][(i + 1) % 3];
      if ((tile_.flags[a] & tile_.flags[b] & 15) != 0) {
        kind_[h] = EdgeKind::Side;  // both ends on one side: the edge runs along it
      } else if ((tile_.heldEdges[t] >> i) & 1U) {
        kind_[h] = ((tile_.riverEdges[t] >> i) & 1U) ? EdgeKind::River : EdgeKind::Line;
      }
    }
    for (std::uint32_t t = 0; t < nt; ++t) push(t);
  }

  std::size_t run() {
    std::size_t inserted = 0;
    while (!heap_.empty() && tri_.size() < options_.maxTriangles) {
      const Entry top = heap_.top();
      heap_.pop();
      if (top.version != version_[top.t]) continue;
      if (!(top.error > options_.tolerance)) break;
      touched_.clear();
      if (improve(top.t)) {
        ++inserted;
        remeasure();
      } else {
        ++version_[top.t];  // nothing to do here: measured, not tried again
        outOfReach_[top.t] = 1;
      }
    }
    writeBack();
    return inserted;
  }

 private:
  struct Entry {
    double error;
    std::uint32_t t;
    std::uint32_t version;
    bool operator<(const Entry& o) const {  // max-heap on error, then lower t
      return error < o.error || (error == o.error && t > o.t);
    }
  };

  [[nodiscard]] Point2 xy(std::uint32_t v) const { return tile_.vertices[v].xy(); }
  [[nodiscard]] std::uint32_t corner(std::uint32_t h) const { return tri_[h / 3][h % 3]; }
  static std::uint32_t next(std::uint32_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
  static std::uint32_t prev(std::uint32_t h) { return h - h % 3 + (h % 3 + 2) % 3; }

  [[nodiscard]] ChordSag sag(std::uint32_t t) const {
    if (!(options_.earthRadius > 0)) return {};
    return chordSag(xy(tri_[t][0]), xy(tri_[t][1]), xy(tri_[t][2]), options_.earthRadius);
  }

  void push(std::uint32_t t) { heap_.push({diff_[t].maxAbs + sag(t).depth, t, version_[t]}); }

  void link(std::uint32_t h, std::uint32_t g) {
    twin_[h] = g;
    if (g != kNone) twin_[g] = h;
  }

  /// Sets triangle t to (a, b, c) with its edges' kinds; twins are linked by
  /// the caller.
  void setTriangle(std::uint32_t t, std::array<std::uint32_t, 3> corners,
                   std::array<EdgeKind, 3> kinds) {
    if (t == tri_.size()) {
      tri_.push_back(corners);
      twin_.insert(twin_.end(), 3, kNone);
      kind_.insert(kind_.end(), 3, EdgeKind::Free);
      diff_.emplace_back();
      version_.push_back(0);
      outOfReach_.push_back(0);
    }
    tri_[t] = corners;
    outOfReach_[t] = 0;
    for (int i = 0; i < 3; ++i) {
      kind_[3 * t + i] = kinds[i];
      vout_[corners[i]] = 3 * t + static_cast<std::uint32_t>(i);
    }
    touched_.push_back(t);
  }

  std::uint32_t addVertex(const Point3& p, std::uint8_t flags) {
    tile_.vertices.push_back(p);
    tile_.flags.push_back(flags);
    vout_.push_back(kNone);
    return static_cast<std::uint32_t>(tile_.vertices.size() - 1);
  }

  /// Restores the constrained Delaunay property around the new vertex v:
  /// `h` is an edge opposite v (v is its triangle's third corner).
  void legalize(std::uint32_t h) {
    std::vector<std::uint32_t> stack{h};
    while (!stack.empty()) {
      const std::uint32_t e = stack.back();
      stack.pop_back();
      const std::uint32_t g = twin_[e];
      if (g == kNone || kind_[e] != EdgeKind::Free) continue;
      const std::uint32_t p = corner(e), q = corner(next(e)), v = corner(prev(e));
      const std::uint32_t o = corner(prev(g));
      if (incircle(xy(p), xy(q), xy(v), xy(o)) <= 0) continue;
      if (orient2d(xy(v), xy(p), xy(o)) <= 0 || orient2d(xy(o), xy(q), xy(v)) <= 0) continue;
      // Flip pq to vo: (p, q, v) + (q, p, o) → (v, p, o) + (o, q, v).
      const std::uint32_t t1 = e / 3, t2 = g / 3;
      const std::uint32_t A = twin_[next(e)], B = twin_[prev(e)];  // q→v, v→p
      const std::uint32_t C = twin_[next(g)], D = twin_[prev(g)];  // p→o, o→q
      const EdgeKind kA = kind_[next(e)], kB = kind_[prev(e)];
      const EdgeKind kC = kind_[next(g)], kD = kind_[prev(g)];
      setTriangle(t1, {v, p, o}, {kB, kC, EdgeKind::Free});
      setTriangle(t2, {o, q, v}, {kD, kA, EdgeKind::Free});
      link(3 * t1, B);
      link(3 * t1 + 1, C);
      link(3 * t1 + 2, 3 * t2 + 2);
      link(3 * t2, D);
      link(3 * t2 + 1, A);
      stack.push_back(3 * t1 + 1);  // p→o, opposite v
      stack.push_back(3 * t2);      // o→q, opposite v
    }
  }

  /// Puts a new vertex strictly inside triangle t.
  bool insertInside(std::uint32_t t, const Point3& p) {
    const std::uint32_t a = tri_[t][0], b = tri_[t][1], c = tri_[t][2];
    const std::uint32_t Eab = twin_[3 * t], Ebc = twin_[3 * t + 1], Eca = twin_[3 * t + 2];
    const EdgeKind kab = kind_[3 * t], kbc = kind_[3 * t + 1], kca = kind_[3 * t + 2];
    const std::uint32_t v = addVertex(p, kHeld | kPinned);
    const auto t1 = static_cast<std::uint32_t>(tri_.size());
    const std::uint32_t t2 = t1 + 1;
    setTriangle(t, {a, b, v}, {kab, EdgeKind::Free, EdgeKind::Free});
    setTriangle(t1, {b, c, v}, {kbc, EdgeKind::Free, EdgeKind::Free});
    setTriangle(t2, {c, a, v}, {kca, EdgeKind::Free, EdgeKind::Free});
    link(3 * t, Eab);
    link(3 * t1, Ebc);
    link(3 * t2, Eca);
    link(3 * t + 1, 3 * t1 + 2);
    link(3 * t1 + 1, 3 * t2 + 2);
    link(3 * t2 + 1, 3 * t + 2);
    legalize(3 * t);
    legalize(3 * t1);
    legalize(3 * t2);
    return true;
  }

  /// Splits edge h (and its twin's triangle, if any) at p, which lies on it
  /// within rounding; false (nothing changed) when a new triangle would not
  /// be strictly counter-clockwise.
  bool splitEdge(std::uint32_t h, const Point3& p, std::uint8_t flags) {
    const std::uint32_t t = h / 3, g = twin_[h];
    const std::uint32_t a = corner(h), b = corner(next(h)), c = corner(prev(h));
    const Point2 q = p.xy();
    if (orient2d(xy(a), q, xy(c)) <= 0 || orient2d(q, xy(b), xy(c)) <= 0) return false;
    std::uint32_t d = kNone;
    if (g != kNone) {
      d = corner(prev(g));
      if (orient2d(xy(b), q, xy(d)) <= 0 || orient2d(q, xy(a), xy(d)) <= 0) return false;
    }
    const EdgeKind kab = kind_[h];
    const std::uint32_t Ebc = twin_[next(h)], Eca = twin_[prev(h)];
    const EdgeKind kbc = kind_[next(h)], kca = kind_[prev(h)];
    const std::uint32_t v = addVertex(p, flags);
    const auto tn = static_cast<std::uint32_t>(tri_.size());
    setTriangle(t, {a, v, c}, {kab, EdgeKind::Free, kca});
    setTriangle(tn, {v, b, c}, {kab, kbc, EdgeKind::Free});
    link(3 * t + 2, Eca);
    link(3 * tn + 1, Ebc);
    link(3 * t + 1, 3 * tn + 2);
    if (g == kNone) {
      twin_[3 * t] = twin_[3 * tn] = kNone;
      legalize(3 * t + 2);
      legalize(3 * tn + 1);
      return true;
    }
    const std::uint32_t t2 = g / 3;
    const std::uint32_t Ead = twin_[next(g)], Edb = twin_[prev(g)];  // a→d, d→b
    const EdgeKind kad = kind_[next(g)], kdb = kind_[prev(g)];
    const auto tm = static_cast<std::uint32_t>(tri_.size());
    setTriangle(t2, {b, v, d}, {kab, EdgeKind::Free, kdb});
    setTriangle(tm, {v, a, d}, {kab, kad, EdgeKind::Free});
    link(3 * t2 + 2, Edb);
    link(3 * tm + 1, Ead);
    link(3 * t2 + 1, 3 * tm + 2);
    link(3 * t2, 3 * tn);  // b→v with v→b
    link(3 * tm, 3 * t);   // v→a with a→v
    legalize(3 * t + 2);
    legalize(3 * tn + 1);
    legalize(3 * t2 + 2);
    legalize(3 * tm + 1);
    return true;
  }

  /// Holds vertex v at the TIN's z; its triangles are measured again.
  bool holdVertex(std::uint32_t v) {
    const auto z = tin_.z(xy(v));
    if (!z) return false;
    tile_.vertices[v].z = *z;
    tile_.flags[v] |= kHeld | kPinned;
    edges_.forget(v);
    // The triangles around v: counter-clockwise from vout, then clockwise
    // when a boundary stops the first walk.
    const std::uint32_t start = vout_[v];
    std::uint32_t h = start;
    do {
      touched_.push_back(h / 3);
      h = twin_[prev(h)];
    } while (h != kNone && h != start);
    if (h == kNone) {
      for (std::uint32_t g = twin_[start]; g != kNone; g = twin_[next(g)])
        touched_.push_back(g / 3);
    }
    return true;
  }

  /// One step at triangle t, the worst: false when nothing can be done there.
  bool improve(std::uint32_t t) {
    const SurfaceDifference& d = diff_[t];
    const std::array<std::uint32_t, 3> v = tri_[t];
    const std::array<Point2, 3> c{xy(v[0]), xy(v[1]), xy(v[2])};
    double longest = 0.0, nearest = HUGE_VAL;
    int nearestCorner = 0;
    for (int i = 0; i < 3; ++i) {
      longest = std::max(longest, std::hypot(c[(i + 1) % 3].x - c[i].x, c[(i + 1) % 3].y - c[i].y));
      const double distance = std::hypot(c[i].x - d.at.x, c[i].y - d.at.y);
      if (distance < nearest) {
        nearest = distance;
        nearestCorner = i;
      }
    }
    // Where the chord's sag is the larger part of the error, the triangle is
    // split where it sags deepest (holding a corner would not change it).
    const ChordSag curvature = sag(t);
    const bool sagging = curvature.depth > d.maxAbs;
    const bool freeCorner = !(tile_.flags[v[nearestCorner]] & kHeld);
    if (!sagging && nearest < 0.1 * longest && freeCorner) return holdVertex(v[nearestCorner]);

    const Rect& rect = tile_.bounds;
    const double margin = options_.sideMargin;
    Point2 p = sagging ? curvature.at : d.vertexAbs > options_.tolerance ? d.vertex : d.at;
    // On a side the error is the side's own (its simplification), which the
    // neighbour shares: nothing in this tile changes it. Beside one, the
    // point comes in to the margin.
    const double onSide = 1e-9 * rect.width();
    if (p.x <= rect.x0 + onSide || p.x >= rect.x1 - onSide || p.y <= rect.y0 + onSide ||
        p.y >= rect.y1 - onSide)
      return false;
    const Point2 worst = p;
    p.x = std::clamp(p.x, rect.x0 + margin, rect.x1 - margin);
    p.y = std::clamp(p.y, rect.y0 + margin, rect.y1 - margin);
    const bool broughtIn = p.x != worst.x || p.y != worst.y;
    // p by its barycentric weights; an edge whose weight is within rounding
    // of zero (or below: p computed a rounding outside) is the edge p is on.
    const double area = geometry::orient2dInexact(c[0], c[1], c[2]);
    if (!(area > 0)) return false;
    auto weight = [&](Point2 q, int i) {  // of corner i: the edge opposite it is i + 1
      const Point2& a = c[(i + 1) % 3];
      const Point2& b = c[(i + 2) % 3];
      return geometry::orient2dInexact(a, b, q) / area;
    };
    constexpr double kOnEdge = 1e-9;
    int edge = -1;
    double least = kOnEdge;
    for (int i = 0; i < 3; ++i) {
      const double w = weight(p, i);
      if (w < least) {
        least = w;
        edge = (i + 1) % 3;  // the edge from corner i + 1 to i + 2
      }
    }
    // Brought in to the margin and out of the triangle (one flat along the
    // side, below the margin line there): nothing this triangle may take
    // reaches its worst point. Splitting the nearest edge at p's foot left
    // the error where it was and the next foot closer, without end — each
    // split flipping the side corner's growing fan (a zoom-1 tile of a
    // mesa: 8.4 M flips, 1 GB, a minute, stopped only by the budget).
    if (broughtIn && least < -kOnEdge) return false;
    for (int i = 0; i < 3; ++i) {
      if (std::hypot(c[i].x - p.x, c[i].y - p.y) <= 1e-9 * longest) {
        return !(tile_.flags[v[i]] & kHeld) && holdVertex(v[i]);
      }
    }
    if (edge < 0) {
      if (orient2d(c[0], c[1], p) <= 0 || orient2d(c[1], c[2], p) <= 0 ||
          orient2d(c[2], c[0], p) <= 0)
        return false;
      const auto z = tin_.z(p);
      return z && insertInside(t, {p.x, p.y, *z});
    }
    const std::uint32_t h = 3 * t + static_cast<std::uint32_t>(edge);
    // p keeps the margin from the sides, so a side edge is never the one it is
    // on; were it, the side stays as it is.
    if (kind_[h] == EdgeKind::Side) return false;
    // On an edge that may be split: at p's foot on it, on the TIN.
    const Point3 a = tile_.vertices[v[edge]], b = tile_.vertices[v[(edge + 1) % 3]];
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double u =
        std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy), 1e-6, 1 - 1e-6);
    const Point2 foot{a.x + u * dx, a.y + u * dy};
    auto z = tin_.z(foot);
    if (!z) return false;
    if (kind_[h] == EdgeKind::River) *z = std::clamp(*z, std::min(a.z, b.z), std::max(a.z, b.z));
    const std::uint8_t flags = kind_[h] == EdgeKind::Free ? kHeld | kPinned : kHeld;
    if (kind_[h] != EdgeKind::Free) ++tile_.breakLineVertices;
    if (splitEdge(h, {foot.x, foot.y, *z}, flags)) return true;
    if (kind_[h] != EdgeKind::Free) --tile_.breakLineVertices;
    return false;
  }

  void remeasure() {
    std::sort(touched_.begin(), touched_.end());
    touched_.erase(std::unique(touched_.begin(), touched_.end()), touched_.end());
    batch_.clear();
    for (std::uint32_t t : touched_) batch_.push_back(tri_[t]);
    const auto fresh = triangleDifferences(tile_.vertices, batch_, tin_, &edges_);
    for (std::size_t k = 0; k < touched_.size(); ++k) {
      const std::uint32_t t = touched_[k];
      diff_[t] = fresh[k];
      ++version_[t];
      push(t);
    }
  }

  void writeBack() {
    tile_.heldEdges.assign(tri_.size(), 0);
    tile_.riverEdges.assign(tri_.size(), 0);
    tile_.error = 0.0;
    tile_.triangleErrors.assign(tri_.size(), 0.0);
    tile_.outOfReach = outOfReach_;
    for (std::uint32_t t = 0; t < tri_.size(); ++t) {
      tile_.triangleErrors[t] = diff_[t].maxAbs;
      for (int i = 0; i < 3; ++i) {
        const auto bit = static_cast<std::uint8_t>(1U << i);
        if (kind_[3 * t + i] != EdgeKind::Free) tile_.heldEdges[t] |= bit;
        if (kind_[3 * t + i] == EdgeKind::River) tile_.riverEdges[t] |= bit;
      }
      if (diff_[t].maxAbs > tile_.error) {
        tile_.error = diff_[t].maxAbs;
        tile_.errorAt = diff_[t].at;
      }
    }
  }

  TileSurface& tile_;
  std::vector<std::array<std::uint32_t, 3>>& tri_;
  const TinIndex& tin_;
  RefineOptions options_;
  EdgeDifferenceCache edges_;  // before diff_, which the constructor measures with it
  std::vector<SurfaceDifference> diff_;
  std::vector<std::uint32_t> twin_;
  std::vector<EdgeKind> kind_;
  std::vector<std::uint32_t> version_;
  std::vector<std::uint8_t> outOfReach_;  // per triangle: improve() could do nothing
  std::vector<std::uint32_t> vout_;
  std::priority_queue<Entry> heap_;
  std::vector<std::uint32_t> touched_;
  std::vector<std::array<std::uint32_t, 3>> batch_;
};

}  // namespace

std::size_t refineTile(TileSurface& tile, const TinIndex& tin, const RefineOptions& options) {
  Refiner refiner(tile, tin, options);
  return refiner.run();
}

}  // namespace tinsmith::tiles
